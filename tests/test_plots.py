"""What the figures draw, read back from the ``matplotlib.figure.Figure`` (no image
comparison): the drawn data against numbers computed here independently, and axes that
cover the data (issue 36, item 4)."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from algid.diagnosis import diagnose
from algid.model.chain import TABLE1
from algid.model.frf import h1_estimate, resolution_hz, segment_samples
from algid.plotting.diagnosis import fig_damping_force, fig_ranking, fig_residuals_spectrum, fig_restoring_force
from algid.plotting.frf import SPAN, frf_figure
from algid.simulator import simulate
from algid.simulator.scenarios import positioning_axis

#: Three lines per force, none shared: every force excites its own frequencies [Hz].
LINES_HZ = np.array([[1.3, 3.7, 7.1], [2.1, 4.3, 9.7], [2.9, 5.3, 12.1]])
FS_HZ = 200.0


def _multisine_record(lines_hz: np.ndarray, duration_s: float = 30.0):
    phases = np.random.default_rng(1).uniform(0, 2 * np.pi, lines_hz.shape)

    def force(t):
        return 2.0 * np.sin(2 * np.pi * lines_hz * t + phases).sum(axis=1)

    r = simulate(TABLE1, force, duration_s, FS_HZ)
    return r.u, r.a


@pytest.fixture(scope="module")
def table1_multisine():
    return _multisine_record(LINES_HZ)


def _finite(line):
    x, y = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)
    keep = np.isfinite(x) & np.isfinite(y)
    return x[keep], y[keep]


def test_frf_draws_the_lines_of_each_force_on_the_model(table1_multisine):
    u, a = table1_multisine
    dt = 1 / FS_HZ
    wanted = resolution_hz(TABLE1)
    assert wanted == pytest.approx(min(TABLE1.modes().damping_ratios * TABLE1.modes().frequencies_hz))
    est = h1_estimate(u, a, dt, nperseg=segment_samples(u.shape[0], dt, wanted, forces=3))
    assert est.resolution_hz <= 1.5 * wanted  # capped by the record: 4 segments of 30 s / 4
    fig = frf_figure(est, TABLE1)
    mag = fig.axes[0]
    lines = mag.get_lines()
    measured, model = lines[0::2], lines[1::2]
    for e, (meas, mod) in enumerate(zip(measured, model)):
        f, h = _finite(meas)
        np.testing.assert_allclose(np.sort(f), LINES_HZ[e], atol=0.01)  # each force's own lines, nowhere else
        truth = np.abs(TABLE1.frf(f)[:, e, e])
        np.testing.assert_allclose(h, truth, rtol=0.05)
        fm, hm = _finite(mod)
        np.testing.assert_allclose(hm, np.abs(TABLE1.frf(fm)[:, e, e]), rtol=1e-12)
    lo, hi = mag.get_xlim()
    assert hi == pytest.approx(SPAN * TABLE1.natural_frequencies_hz().max())  # not the Nyquist rate
    assert lo <= LINES_HZ.min() and hi >= LINES_HZ.max()
    top = max(np.nanmax(np.abs(est.H[:, e, e])) for e in range(3))
    assert mag.get_ylim()[1] >= top  # the highest measured point is on the axes


def test_frf_draws_nothing_where_the_forces_are_not_separable():
    u, a = _multisine_record(np.tile(LINES_HZ[:1], (3, 1)), duration_s=12.0)  # the same lines on all
    est = h1_estimate(u, a, 1 / FS_HZ)
    assert not est.excited.any() and np.isnan(est.H).all()
    fig = frf_figure(est, TABLE1)
    assert all(line.get_linestyle() == "--" for line in fig.axes[0].get_lines())  # the model alone
    assert "not separable" in fig._suptitle.get_text()


def test_segment_samples_follow_the_resolution_within_the_record():
    assert segment_samples(100_000, 1e-3, 0.25) == 4000  # 0.25 Hz bins
    assert segment_samples(10_000, 1e-3, 0.05, forces=3) == 2500  # capped: 7 half-overlapping segments
    with pytest.raises(ValueError, match="resolution must be > 0"):
        segment_samples(1000, 1e-3, 0.0)


@pytest.fixture(scope="module")
def axis_friction():
    """An encoder-only positioning axis with dry friction (velocities well under 1 m/s)."""
    effect = {"name": "coulomb_friction", "location": {"dof": 1}, "params": {"force": 3.0}}
    sc = positioning_axis(seed=0, duration_s=4.0, effects=[effect])
    return sc, diagnose(sc.recording)


def test_damping_and_restoring_force_axes_follow_the_data(axis_friction):
    sc, d = axis_friction
    v_true = np.gradient(sc.recording.x[:, 0], sc.recording.dt)
    fig = fig_damping_force(d)
    x, _ = _finite(fig.axes[0].get_lines()[0])  # the scatter of the damping force
    assert np.abs(x).max() == pytest.approx(np.abs(v_true).max(), rel=0.1)  # the record's velocities
    lo, hi = fig.axes[0].get_xlim()
    assert lo <= x.min() and hi >= x.max() and hi - lo < 3 * np.ptp(v_true)
    fig = fig_restoring_force(d)
    bottom = fig.axes[1]
    r = -d.lin.resid_force[:, 0]  # one DOF: the spring carries the whole unexplained force
    _, drawn = _finite(bottom.get_lines()[0])
    assert drawn.min() == pytest.approx(r.min()) and drawn.max() == pytest.approx(r.max())
    lo, hi = bottom.get_ylim()
    assert lo <= r.min() and hi >= r.max()


def _stencil_gain(f_hz: np.ndarray, dt: float) -> np.ndarray:
    """|gain| of the five-point central second difference (-1, 16, -30, 16, -1) / 12 dt^2."""
    w = 2 * np.pi * f_hz * dt
    return np.abs(-2 * np.cos(2 * w) + 32 * np.cos(w) - 30) / 12 / dt**2


def test_residual_spectrum_draws_the_encoder_noise_in_the_residuals_scaling(axis_friction):
    sc, d = axis_friction
    dt = sc.recording.dt
    fig = fig_residuals_spectrum(d)
    ax = fig.axes[0]
    by_label = {line.get_label(): line for line in ax.get_lines()}
    f, noise = _finite(by_label["sensor noise (noise model)"])
    _, linear = _finite(by_label["error, linear model"])
    # the noise model of encoder counts: quantisation, q^2 / 12 white up to Nyquist, twice differentiated
    q = sc.info["encoder_m"]
    expected = q * q / 12 * 2 * dt * _stencil_gain(f, dt) ** 2
    top = f > 250.0  # there the differentiated noise is all the equation error holds
    assert np.median(noise[top] / expected[top]) == pytest.approx(1.0, rel=0.25)
    assert np.median(linear[top] / noise[top]) == pytest.approx(1.0, rel=0.5)
    assert np.median(noise[f < 20.0]) < 1e-2 * np.median(noise[top])  # not a flat line


def _overlaps(fig, axis) -> int:
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    boxes = [t.get_window_extent(renderer) for t in axis.get_ticklabels() if t.get_visible() and t.get_text()]
    return sum(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :])


def test_tick_labels_do_not_run_into_each_other(axis_friction):
    _, d = axis_friction
    ranking = fig_ranking(d)
    assert _overlaps(ranking, ranking.axes[0].xaxis) == 0
    assert _overlaps(ranking, ranking.axes[0].yaxis) == 0
    damping = fig_damping_force(d)
    assert all(_overlaps(damping, ax.xaxis) == 0 and _overlaps(damping, ax.yaxis) == 0 for ax in damping.axes)
