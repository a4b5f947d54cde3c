"""Recording IO: round trips, one-line errors for every malformed input, and the
acceleration derived from displacements against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from algid.recording import (
    Recording,
    RecordingError,
    accelerations,
    derivative_weights,
    load_recording,
    save_recording,
    second_derivative,
)


def _rec(T=200, n=3, dt=1e-3, with_a=True, with_x=False, seed=0):
    rng = np.random.default_rng(seed)
    t = 0.5 + dt * np.arange(T)
    return Recording(
        t=t,
        u=rng.standard_normal((T, n)),
        a=rng.standard_normal((T, n)) if with_a else None,
        x=rng.standard_normal((T, n)) if with_x else None,
    )


def _write(tmp_path, text, name="r.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _csv_text(T=20, n=2, dt=1e-3, cols=None):
    cols = cols or ["t"] + [f"u{i}" for i in range(1, n + 1)] + [f"a{i}" for i in range(1, n + 1)]
    lines = [",".join(cols)]
    for k in range(T):
        vals = [f"{k * dt:.6f}"] + [f"{0.1 * k + j:.3f}" for j in range(len(cols) - 1)]
        lines.append(",".join(vals))
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("ext", [".csv", ".npz"])
@pytest.mark.parametrize("with_a,with_x", [(True, False), (True, True), (False, True)])
def test_round_trip_is_exact(tmp_path, ext, with_a, with_x):
    rec = _rec(with_a=with_a, with_x=with_x)
    back = load_recording(save_recording(tmp_path / f"r{ext}", rec))
    assert back.n == 3 and back.path.name == f"r{ext}"
    assert back.dt == pytest.approx(1e-3, rel=1e-12)
    np.testing.assert_array_equal(back.t, rec.t)
    np.testing.assert_array_equal(back.u, rec.u)
    for name in ("a", "x"):
        if getattr(rec, name) is None:
            assert getattr(back, name) is None
        else:
            np.testing.assert_array_equal(getattr(back, name), getattr(rec, name))


def test_csv_any_column_order_comments_and_whitespace(tmp_path):
    text = "# rig 7, 2024\n a1 , t ,u1\n1.0, 0.000, 5\n\n2.0,0.001,6\n" + "".join(
        f"{3 + k}.0,{0.002 + 0.001 * k:.3f},{7 + k}\n" for k in range(8)
    )
    rec = load_recording(_write(tmp_path, text))
    assert rec.n == 1 and rec.x is None
    np.testing.assert_allclose(rec.a[:3, 0], [1.0, 2.0, 3.0])
    np.testing.assert_allclose(rec.u[:3, 0], [5.0, 6.0, 7.0])
    assert rec.dt == pytest.approx(1e-3)


ERRORS = [
    ("", "empty file"),
    ("# only a comment\n", "empty file"),
    ("t,u1,a1\n", "no data rows"),
    (_csv_text(cols=["t", "u1", "u2", "a1"]), "mismatched n: force columns u1..u2"),
    (_csv_text(cols=["t", "u1", "u2", "u3", "a1", "a3", "x1", "x2", "x3"]), "missing column a2"),
    (_csv_text(cols=["t", "u1", "a1", "a2"]), "mismatched n"),
    (_csv_text(cols=["u1", "a1"]), "missing column 't'"),
    (_csv_text(cols=["t", "a1"]), "missing force columns"),
    (_csv_text(cols=["t", "u1"]), "missing columns a1"),
    (_csv_text(cols=["t", "u1", "a1", "a1"]), "duplicate column 'a1'"),
    (_csv_text(cols=["t", "u2", "a2"]), "missing column u1"),
    ("t,u1,a1\n" + "".join(f"{k}e-3,1,2\n" for k in range(9)) + "9e-3,1\n", "ragged row at line 11"),
    ("t,u1,a1\n" + "".join(f"{k}e-3,1,2\n" for k in range(9)) + "9e-3,1,abc\n", "cannot parse 'abc'"),
    ("t,u1,a1\n" + "".join(f"{'nan' if k == 4 else f'{k}e-3'},1,2\n" for k in range(10)), "column t has NaN at line 6"),
    ("t,u1,a1\n" + "".join(f"{k}e-3,{'inf' if k % 3 else 1},2\n" for k in range(30)), "67 % of the samples miss"),
    (
        "t,u1,a1\n" + "".join(f"{k}e-3,1,{'nan' if 5 <= k < 15 else 2}\n" for k in range(30)),
        "a1 misses 10 samples in a row from line 7",
    ),
    ("t,u1,a1\n" + "".join(f"{k}e-3,1,2\n" for k in (0, 1, 2, 3, 3, 4, 5, 6, 7, 8)), "not increasing at line 6"),
    ("t,u1,a1\n" + "".join(f"{k}e-3,1,2\n" for k in (0, 1, 2, 3, 4, 5, 6, 8, 9, 10)), "non-uniform time"),
    ("t,u1,a1\n0,1,2\n0.001,1,2\n", "too short"),
]


@pytest.mark.parametrize("text,needle", ERRORS)
def test_csv_errors_are_one_line_and_name_the_problem(tmp_path, text, needle):
    with pytest.raises(RecordingError) as info:
        load_recording(_write(tmp_path, text))
    msg = str(info.value)
    assert "\n" not in msg and needle in msg, msg
    assert isinstance(info.value, ValueError)


def test_timestamps_as_loggers_write_them(tmp_path):
    """A 2048 Hz record whose time column is rounded to microseconds is uniform at 2048 Hz,
    with a note; timestamps jittered by 5 % of a step too; a missing sample is not, and the
    message says what to do; --dt replaces the column."""
    T = 200
    rows = lambda t: "t,u1,a1\n" + "".join(f"{x},1,2\n" for x in t)  # noqa: E731
    rec = load_recording(_write(tmp_path, rows(np.round(np.arange(T) / 2048, 6))))
    assert rec.fs_hz == pytest.approx(2048, rel=1e-6)
    assert rec.t[5] == pytest.approx(5 / 2048, abs=1e-7)  # the timestamps hold +-0.5 us
    assert any("taken as uniform at 2048" in n for n in rec.notes), rec.notes
    jitter = 0.05 * np.random.default_rng(0).uniform(-1, 1, T) / 1000
    rec = load_recording(_write(tmp_path, rows(np.arange(T) / 1000 + jitter), "j.csv"))
    assert rec.fs_hz == pytest.approx(1000, rel=1e-3)
    gap = np.delete(np.arange(T + 1), 50) / 1000
    with pytest.raises(RecordingError, match="non-uniform time.*resample.*--rate HZ"):
        load_recording(_write(tmp_path, rows(gap), "g.csv"))
    rec = load_recording(_write(tmp_path, rows(gap), "g.csv"), dt=1e-3)
    assert rec.dt == pytest.approx(1e-3) and any("replaced" in n for n in rec.notes)


def test_file_level_errors(tmp_path):
    with pytest.raises(RecordingError, match="unknown extension '.json'"):
        load_recording(_write(tmp_path, "t,u1,a1\n", "r.json"))
    with pytest.raises(RecordingError, match="no such file"):
        load_recording(tmp_path / "missing.csv")
    with pytest.raises(RecordingError, match="not a readable .npz"):
        load_recording(_write(tmp_path, "garbage", "r.npz"))
    (tmp_path / "bin.csv").write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(RecordingError, match="cannot decode"):
        load_recording(tmp_path / "bin.csv")


def test_npz_errors(tmp_path):
    t = 1e-3 * np.arange(10)
    p = tmp_path / "r.npz"
    np.savez(p, t=t, u1=np.ones(10), a1=np.ones(9))
    with pytest.raises(RecordingError, match="ragged arrays: 'a1' has 9 samples"):
        load_recording(p)
    np.savez(p, t=t, u1=np.ones((10, 1)), a1=np.ones(10))
    with pytest.raises(RecordingError, match="expected 1-D"):
        load_recording(p)
    np.savez(p, t=t, u1=np.ones(10), u2=np.ones(10), x1=np.ones(10))
    with pytest.raises(RecordingError, match="mismatched n: force columns u1..u2 but displacement"):
        load_recording(p)
    a = np.ones(10)
    a[3:] = np.nan
    np.savez(p, t=t, u1=np.ones(10), a1=a)
    with pytest.raises(RecordingError, match="70 % of the samples miss a value"):
        load_recording(p)
    np.savez(p)
    with pytest.raises(RecordingError, match="empty file"):
        load_recording(p)


def test_constructor_validates():
    t = 1e-3 * np.arange(10)
    with pytest.raises(RecordingError, match="need accelerations"):
        Recording(t=t, u=np.ones((10, 2)))
    with pytest.raises(RecordingError, match="mismatched n"):
        Recording(t=t, u=np.ones((10, 2)), a=np.ones((10, 3)))
    with pytest.raises(RecordingError, match="dt = 0.002 given"):
        Recording(t=t, u=np.ones(10), a=np.ones(10), dt=0.002)
    rec = Recording(t=t, u=np.ones(10), a=np.ones(10))
    assert rec.u.shape == (10, 1) and rec.n == 1 and rec.fs_hz == pytest.approx(1000.0)


def test_derivative_weights_match_textbook_stencils():
    np.testing.assert_allclose(derivative_weights(3, 2, 1), [1, -2, 1], atol=1e-12)
    np.testing.assert_allclose(derivative_weights(5, 2, 2), np.array([-1, 16, -30, 16, -1]) / 12, atol=1e-12)
    np.testing.assert_allclose(derivative_weights(3, 1, 1), [-0.5, 0, 0.5], atol=1e-12)
    np.testing.assert_allclose(derivative_weights(3, 2, 0), [1, -2, 1], atol=1e-12)  # parabola: same everywhere


@pytest.mark.parametrize("points", [3, 5, 7])
def test_second_derivative_exact_on_polynomials_of_its_degree(points):
    dt = 1e-3
    t = 0.3 + dt * np.arange(50)
    rng = np.random.default_rng(points)
    coef = rng.standard_normal(points)  # degree points-1
    x = np.polyval(coef, t - 0.31)
    exact = np.polyval(np.polyder(coef, 2), t - 0.31)
    np.testing.assert_allclose(second_derivative(x, dt, points), exact, rtol=0, atol=1e-5 * np.abs(exact).max())


def test_second_derivative_convergence_order_on_a_sine():
    # Interior error of the 5-point central stencil is dt^4 x^(6)/90: order 4.
    f = 7.0
    errs = []
    for fs in (200.0, 400.0, 800.0):
        dt = 1 / fs
        t = dt * np.arange(int(fs))
        x = np.sin(2 * np.pi * f * t + 0.3)
        a = second_derivative(x, dt, 5)
        exact = -((2 * np.pi * f) ** 2) * np.sin(2 * np.pi * f * t + 0.3)
        err = np.abs(a - exact)[5:-5].max() / (2 * np.pi * f) ** 2
        predicted = (2 * np.pi * f * dt) ** 4 / 90
        assert err == pytest.approx(predicted, rel=0.02)
        errs.append(err)
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    np.testing.assert_allclose(orders, 4.0, atol=0.05)


def test_accelerations_from_displacement_recording():
    dt = 1e-3
    t = dt * np.arange(2000)
    w = 2 * np.pi * np.array([3.0, 11.0])
    x = np.stack([np.sin(w[0] * t), 0.2 * np.cos(w[1] * t)], axis=1)
    exact = -(w**2) * x
    rec = Recording(t=t, u=np.zeros((t.size, 2)), x=x)
    a = accelerations(rec)
    err = np.abs(a - exact) / np.abs(exact).max(axis=0)
    # Interior: the central stencil's dt^4 x^(6)/90; the two samples at each end use
    # one-sided stencils, one order lower.
    assert np.all(err[2:-2].max(axis=0) < (w * dt) ** 4 / 90 * 1.01)
    assert np.all(err.max(axis=0) < (w * dt) ** 3)
    # Measured accelerations are passed through untouched.
    rec2 = Recording(t=t, u=np.zeros((t.size, 2)), a=exact, x=x)
    assert accelerations(rec2) is rec2.a


def test_noise_gain_of_the_default_stencil():
    rng = np.random.default_rng(1)
    dt = 1e-3
    noise = 1e-6 * rng.standard_normal(200_000)
    a = second_derivative(noise, dt)
    gain = math.sqrt(1 + 256 + 900 + 256 + 1) / 12
    assert a[10:-10].std() == pytest.approx(gain * 1e-6 / dt**2, rel=0.02)


@pytest.mark.parametrize("points", [3, 5, 7])
def test_first_derivative_exact_on_polynomials_and_of_order_points_minus_1(points):
    from algid.recording import derivative

    dt = 1e-3
    t = 0.3 + dt * np.arange(40)
    coef = np.random.default_rng(points).standard_normal(points)
    v = np.polyval(coef, t - 0.31)
    exact = np.polyval(np.polyder(coef, 1), t - 0.31)
    np.testing.assert_allclose(derivative(v, dt, 1, points), exact, rtol=0, atol=1e-7 * np.abs(exact).max())
    errs = []
    for fs in (200.0, 400.0, 800.0):
        tt = np.arange(int(fs)) / fs
        d = derivative(np.sin(2 * np.pi * 7.0 * tt), 1 / fs, 1, points)
        errs.append(np.abs(d - 2 * np.pi * 7.0 * np.cos(2 * np.pi * 7.0 * tt))[points:-points].max())
    np.testing.assert_allclose(np.log2(np.array(errs[:-1]) / np.array(errs[1:])), points - 1, atol=0.1)


def test_velocity_recording_csv_and_its_accelerations(tmp_path):
    dt = 1e-3
    t = dt * np.arange(500)
    w = 2 * np.pi * 5.0
    path = tmp_path / "vib.csv"
    path.write_text(
        "t,u1,v1\n" + "\n".join(f"{tk:.17g},{np.sin(w * tk):.17g},{np.cos(w * tk):.17g}" for tk in t) + "\n"
    )
    rec = load_recording(path)
    assert rec.v is not None and rec.a is None and rec.x is None
    a = accelerations(rec)
    np.testing.assert_allclose(a[2:-2, 0], -w * np.sin(w * t[2:-2]), atol=(w * dt) ** 4 / 30 * w)
    assert "v1" in rec.columns()
    with pytest.raises(RecordingError, match="velocities"):
        Recording(t=t, u=np.zeros((t.size, 1)))
