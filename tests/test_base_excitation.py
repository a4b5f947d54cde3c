"""Base excitation (a shake table): the support motion a0 in recordings, the augmented chain
of identify, and the chain known up to scale without a force."""

from __future__ import annotations

import numpy as np
import pytest

from algid.identification.base import SCALE_REASON, augment, cumulative_integral
from algid.identification.engine import identify
from algid.identification.motion import Motion, chain_forces
from algid.model.chain import TABLE1, Chain
from algid.model.modal import modes
from algid.recording import Recording, RecordingError, load_recording, save_recording
from algid.recording.units import STANDARD_GRAVITY
from algid.simulator.base import SupportMotion, simulate_base

T_S = np.arange(200) * 1e-3


def _shake_table_csv(path, columns: dict[str, np.ndarray]) -> None:
    names = list(columns)
    table = np.column_stack([columns[k] for k in names])
    np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt="%.17g")


def test_shake_table_csv_reads_support_acceleration_in_g(tmp_path):
    a = np.sin(np.outer(T_S, [3.0, 5.0, 7.0]))
    path = tmp_path / "shake.csv"
    _shake_table_csv(path, {"time [s]": T_S, "a0 [g]": a[:, 0], "a1 [g]": a[:, 1], "a2 [g]": a[:, 2]})
    rec = load_recording(path)
    assert rec.n == 2 and rec.base_kind == "a"
    np.testing.assert_allclose(rec.base, a[:, 0] * STANDARD_GRAVITY, rtol=1e-15)
    np.testing.assert_allclose(rec.a, a[:, 1:] * STANDARD_GRAVITY, rtol=1e-15)
    assert not np.any(rec.u)


def test_npz_support_displacement_with_force_on_one_dof(tmp_path):
    path = tmp_path / "rig.npz"
    np.savez(path, t=T_S, **{"x0 [mm]": np.sin(T_S), "u2": np.cos(T_S), "a1": T_S, "a2": 2 * T_S})
    rec = load_recording(path)
    assert rec.base_kind == "x"
    np.testing.assert_allclose(rec.base, 1e-3 * np.sin(T_S))
    np.testing.assert_array_equal(rec.u[:, 0], 0.0)
    np.testing.assert_array_equal(rec.u[:, 1], np.cos(T_S))
    back = load_recording(save_recording(tmp_path / "back.npz", rec))
    np.testing.assert_array_equal(back.base, rec.base)
    np.testing.assert_array_equal(back.u, rec.u)


def test_record_without_force_nor_support_motion_is_refused(tmp_path):
    path = tmp_path / "bare.csv"
    _shake_table_csv(path, {"t": T_S, "a1": T_S, "a2": T_S})
    with pytest.raises(RecordingError, match=r"missing force columns u1..un \(or the support's acceleration a0"):
        load_recording(path)
    with pytest.raises(RecordingError, match="no force columns"):
        Recording(t=T_S, u=None, a=np.ones((200, 2)))


def test_a_support_motion_alone_is_refused(tmp_path):
    """Found by the reader's fuzzing: a0 and no DOF's motion (nor force) is one clear line."""
    path = tmp_path / "support.csv"
    _shake_table_csv(path, {"t": T_S, "a0": T_S})
    with pytest.raises(RecordingError, match=r"missing columns a1..an \(or velocities v1..vn"):
        load_recording(path)


def test_two_support_motions_are_refused(tmp_path):
    path = tmp_path / "two.csv"
    _shake_table_csv(path, {"t": T_S, "a0": T_S, "x0": T_S, "a1": T_S})
    with pytest.raises(RecordingError, match="two support motions a0, x0: keep one"):
        load_recording(path)


def test_dof1_equation_is_the_augmented_chains():
    """m1 a1 + c1 v1 + k1 (x1 - x0) + k2 (x1 - x2) = DOF 1's row of the (n+1)-DOF chain
    whose first mass is the support (its m0, c0, k0 anything)."""
    rng = np.random.default_rng(3)
    x, v, a = (rng.standard_normal((50, 4)) for _ in range(3))  # support + 3 DOF
    m, c, k = TABLE1.mass, TABLE1.damping, TABLE1.stiffness
    direct = m[0] * a[:, 1] + c[0] * v[:, 1] + k[0] * (x[:, 1] - x[:, 0]) + k[1] * (x[:, 1] - x[:, 2])
    theta = np.concatenate([[7.0, *m], [0.3, *c], [11.0, *k]])
    rows = chain_forces(theta, 4, "fixed", Motion(x, v, a))
    np.testing.assert_allclose(rows[:, 1], direct, rtol=1e-13)


def test_cumulative_integral_of_a_cubic_is_exact():
    t = np.linspace(0.0, 1.0, 101)
    y = 1 - 2 * t + 3 * t**2 - 4 * t**3
    np.testing.assert_allclose(cumulative_integral(y, t[1]), t - t**2 + t**3 - t**4, atol=1e-14)


def test_support_equation_scales_the_chain_without_force():
    rec = Recording(t=T_S, u=None, a=np.sin(np.outer(T_S, [5.0, 7.0])), base=np.cos(3 * T_S))
    aug, scale = augment(rec)
    assert scale == SCALE_REASON and aug.n == 3
    np.testing.assert_allclose(
        np.gradient(np.gradient(aug.u[:, 0], 1e-3), 1e-3)[5:-5], (aug.a[:, 0] - aug.a[:, 1])[5:-5], atol=1e-3
    )


def _ratio_truth(chain: Chain, name: str) -> float:
    top, bottom = name.split("/")
    value = (chain.damping if top[0] == "c" else chain.stiffness)[int(top[1:]) - 1]
    return value / chain.mass[int(bottom[1:]) - 1]


def test_noise_free_ratios_are_exact():
    rec = simulate_base(TABLE1, SupportMotion.random(2.0, band_hz=(0.5, 10.0), seed=2), 2.0)
    r = identify(rec)
    assert r.plan.estimator == "window" and r.scale == SCALE_REASON
    assert len(r.ratios) == 9
    for name, ratio in r.ratios.items():
        assert ratio["value"] == pytest.approx(_ratio_truth(TABLE1, name), rel=1e-6), name


def test_support_only_modal_table_and_masses_not_identifiable():
    """Table 1, 20 s at 40 dB, support acceleration only."""
    rec = simulate_base(TABLE1, SupportMotion.random(20.0, seed=1), 20.0, noise_db=40.0, seed=1)
    r = identify(rec)
    est, true = r.modes()[0].modes, modes(TABLE1).modes
    for e, t in zip(est, true):
        assert e.frequency_hz == pytest.approx(t.frequency_hz, rel=0.005)
        assert e.damping_ratio == pytest.approx(t.damping_ratio, rel=0.05)
        assert 0 < e.sigma_frequency_hz < 0.01 * e.frequency_hz
    masses = [v for v in r.verdicts if v.name[0] == "m"]
    assert all(v.status == "not_identifiable" and v.reason == SCALE_REASON for v in masses)
    assert all(ratio["valid"] for ratio in r.ratios.values())
    doc = r.to_json()
    assert doc["mass"] == [None] * 3 and doc["scale"] == SCALE_REASON
    assert doc["ratios"]["k1/m1"]["value"] == pytest.approx(500.0, rel=0.01)
    assert "skipped" in doc["model_fit"] and doc["modes"] is not None


@pytest.mark.slow
def test_force_on_dof1_gives_the_full_scale():
    def force(t):
        return np.array([30 * np.sin(2 * np.pi * 1.7 * t) + 20 * np.sin(2 * np.pi * 4.9 * t + 1), 0.0, 0.0])

    rec = simulate_base(TABLE1, SupportMotion.random(20.0, seed=1), 20.0, noise_db=40.0, seed=1, force=force)
    r = identify(rec)
    truth = np.concatenate([TABLE1.mass, TABLE1.damping, TABLE1.stiffness])
    assert r.plan.method == "algebraic" and not r.scale
    np.testing.assert_allclose(r.theta, truth, rtol=0.03)
    assert r.valid


def test_diagnose_refuses_a_base_excited_record_clearly():
    from algid.diagnosis.engine import diagnose

    rec = Recording(t=T_S, u=None, a=np.sin(np.outer(T_S, [5.0, 7.0])), base=np.cos(3 * T_S))
    with pytest.raises(RecordingError, match="base-excited record .* run `algid identify`"):
        diagnose(rec)
