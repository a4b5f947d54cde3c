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


def test_restoring_force_draws_the_spring_force_the_equations_leave(axis_friction):
    """Upper panel: against the spring's deformation (the encoder's positions, in mm), the
    linear spring's force plus the unexplained force (eq. 1 without the spring's own linear
    term), and the linear law through zero with the fitted stiffness."""
    sc, d = axis_friction
    rec, P = sc.recording, d.P
    fig = fig_restoring_force(d)
    top = fig.axes[0]
    scatter, law = top.get_lines()[:2]
    deformation = rec.x[np.rint((P.t - rec.t[0]) / rec.dt).astype(int), 0]  # one DOF: the spring stretches by x1
    x_mm, force = _finite(scatter)
    assert x_mm.size == P.t.size  # every sample (the record is short)
    # the states reconstructed per window: the encoder's positions to a few counts (1e-4 of the stroke)
    np.testing.assert_allclose(x_mm / 1e3, deformation, atol=1e-4 * np.ptp(deformation))
    k = d.lin.stiffness()[0]
    np.testing.assert_allclose(force, k * x_mm / 1e3 - d.lin.resid_force[:, 0], rtol=1e-12, atol=1e-12)
    lx, ly = _finite(law)
    assert lx == pytest.approx([x_mm.min(), x_mm.max()])
    np.testing.assert_allclose(ly, k * lx / 1e3, rtol=1e-9)
    assert f"{k:.4g}" in law.get_label()
    assert _inside(top, force)


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


@pytest.mark.slow
def test_residual_spectrum_draws_the_accelerometer_noise_under_dry_friction():
    """A Table 1 multisine record at 60 dB with 1.5 N of Coulomb friction on DOF 1, measured
    accelerations: the floor drawn is the sensor noise's own spectrum in the equation errors
    (the same record's noise alone, ``a_noise - u_noise / m``), not the friction's jumps."""
    from scipy.signal import welch

    from algid.plotting.diagnosis import noise_spectrum, spectrum_segment
    from algid.simulator.scenarios import fleet_recording

    effect = {"name": "coulomb_friction", "location": {"dof": 1}, "params": {"force": 1.5}}
    rec = fleet_recording(TABLE1, 20.0, 0, effect, noise_db=60.0)
    clean = fleet_recording(TABLE1, 20.0, 0, effect, noise_db=None)
    d = diagnose(rec)
    assert d.effect == "coulomb_friction" and d.location == {"dof": 1}
    assert d.P.form == "acceleration" and d.P.forced.all()
    sensor = (rec.a - clean.a) - (rec.u - clean.u) / TABLE1.mass[None, :]
    nper = spectrum_segment(d)
    _, truth = welch(sensor, fs=1 / rec.dt, nperseg=nper, axis=0)
    ratio = np.median(noise_spectrum(d, nper)[1:] / truth[1:], axis=0)
    assert np.all((ratio > 0.7) & (ratio < 1.5)), ratio


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


def _collection_y_range(collection) -> tuple[float, float]:
    y = np.concatenate([p.vertices[:, 1] for p in collection.get_paths()])
    return float(y.min()), float(y.max())


def _inside(ax, y: np.ndarray) -> bool:
    lo, hi = ax.get_ylim()
    return bool(lo <= np.nanmin(y) and hi >= np.nanmax(y))


@pytest.fixture(scope="module")
def table1_identified():
    from algid.identification.engine import identify
    from algid.recording import Recording

    lines = np.array([[1.3, 3.7], [2.1, 4.3], [2.9, 5.3]])
    r = simulate(TABLE1, lambda t: 2.0 * np.sin(2 * np.pi * lines * t + 1.0).sum(axis=1), 20.0, FS_HZ)
    return identify(Recording(t=r.t, u=r.u, a=r.a), replicates=2)


def test_estimates_draw_every_history_relative_to_its_final_value(table1_identified):
    from algid.plotting.identify import estimates_figure

    res = table1_identified
    rows = min(res.history.shape[0], res.history_sigma.shape[0])
    t, H, S = res.time_s[-rows:], res.history[-rows:], res.history_sigma[-rows:]
    fig = estimates_figure(res)
    names = [v.name for v in res.verdicts]
    for ax, family in zip(fig.axes, "mck"):
        drawn = [line for line in ax.get_lines() if not line.get_label().startswith("_")]
        wanted = [p for p, nm in enumerate(names) if nm[0] == family]
        assert [line.get_label().split(" = ")[0] for line in drawn] == [names[p] for p in wanted]
        for line, band, p in zip(drawn, ax.collections, wanted):
            rel = 100.0 * (H[:, p] - res.theta[p]) / res.theta[p]
            np.testing.assert_allclose(line.get_xdata(), t)
            np.testing.assert_allclose(line.get_ydata(), rel, rtol=1e-9, atol=1e-12)
            assert f"{res.theta[p]:.4g}" in line.get_label()
            sigma = 100.0 * S[:, p] / abs(res.theta[p])
            assert _collection_y_range(band) == pytest.approx((np.nanmin(rel - sigma), np.nanmax(rel + sigma)))
            assert _inside(ax, rel[rows // 2 :])  # the settled half is on the axes


@pytest.fixture(scope="module")
def demo_run():
    from algid.control import demo

    return demo.run_scenario(n=2, duration_s=0.5)


def _demo_truth(chain) -> dict[str, np.ndarray]:
    """The demo chain's parameters per family, fixed at both ends (every spring estimated)."""
    return {"mass": chain.mass, "damping": chain.damping, "stiffness": chain.stiffness}


def test_demo_estimates_draw_the_estimates_and_the_true_values(demo_run):
    from algid.plotting.demo import estimates_figure

    res, summary = demo_run
    truth = _demo_truth(res.chain)
    fig = estimates_figure(res, summary)
    zoom = res.t <= 0.25
    for row, family in enumerate(("mass", "damping", "stiffness")):
        est = np.asarray(res.estimates[family], float)
        for col, mask in enumerate((zoom, np.ones_like(zoom))):
            ax = fig.axes[2 * row + col]
            curves = [line for line in ax.get_lines() if np.size(line.get_xdata()) > 2]
            levels = [line.get_ydata()[0] for line in ax.get_lines() if line.get_linestyle() == "--"]
            assert len(curves) == truth[family].size
            for q, line in enumerate(curves):
                np.testing.assert_array_equal(line.get_xdata(), res.t[mask])
                np.testing.assert_array_equal(line.get_ydata(), est[mask, q])
            np.testing.assert_allclose(levels, truth[family])
            assert _inside(ax, truth[family])


def test_demo_positions_and_forces_draw_the_loop(demo_run):
    from algid.plotting.demo import forces_figure, positions_figure

    res, summary = demo_run
    fig = positions_figure(res, summary)
    top, bottom = fig.axes
    for i in range(res.chain.n):
        np.testing.assert_allclose(top.get_lines()[2 * i].get_ydata(), 1e3 * res.x[:, i])
        np.testing.assert_allclose(top.get_lines()[2 * i + 1].get_ydata(), 1e3 * res.x_ref[:, i])
        np.testing.assert_allclose(bottom.get_lines()[i].get_ydata(), 1e6 * (res.x[:, i] - res.x_ref[:, i]))
    assert _inside(top, 1e3 * res.x) and _inside(bottom, 1e6 * (res.x - res.x_ref))
    # the force an exact model needs along the reference: M a* + C v* + K x*, eq. 1 written out
    ch, log = res.chain, res.controller_log
    k_left, k_right = ch.stiffness[:-1], ch.stiffness[1:]
    x_ref = res.x_ref
    x_prev = np.hstack([np.zeros((x_ref.shape[0], 1)), x_ref[:, :-1]])
    x_next = np.hstack([x_ref[:, 1:], np.zeros((x_ref.shape[0], 1))])
    exact = (
        ch.mass * log["xdd_ref"] + ch.damping * log["xd_ref"] + k_left * (x_ref - x_prev) + k_right * (x_ref - x_next)
    )
    fig = forces_figure(res, summary)
    top, bottom = fig.axes
    near = (res.t >= summary["switch_time_s"] - 0.05) & (res.t <= summary["switch_time_s"] + 0.2)
    for i in range(ch.n):
        np.testing.assert_allclose(top.get_lines()[i].get_ydata(), res.u_applied[:, i])
        deviation = 1e3 * (res.u_applied[near, i] - exact[near, i])
        np.testing.assert_allclose(bottom.get_lines()[i].get_ydata(), deviation, rtol=1e-9, atol=1e-9)
        assert _inside(bottom, deviation)
    assert _inside(top, res.u_applied)


def test_demo_estimation_error_draws_the_relative_errors(demo_run):
    from algid.plotting.demo import estimation_error_figure

    res, summary = demo_run
    truth = _demo_truth(res.chain)
    fig = estimation_error_figure(res, summary)
    for ax, family in zip(fig.axes[:3], ("mass", "damping", "stiffness")):
        est = np.asarray(res.estimates[family], float)
        for q, line in enumerate(ax.get_lines()[: truth[family].size]):
            np.testing.assert_allclose(
                line.get_ydata(), np.abs(est[:, q] - truth[family][q]) / truth[family][q], rtol=1e-9, atol=1e-14
            )
    drift = fig.axes[3]
    for line, key in zip(drift.get_lines(), ("single_history", "continuous_history")):
        h = np.asarray(res.drift[key], float)
        worst = np.array([np.max(row[np.isfinite(row)]) if np.isfinite(row).any() else np.nan for row in h])
        np.testing.assert_allclose(line.get_ydata(), worst)


@pytest.fixture(scope="module")
def fleet_table():
    pd = pytest.importorskip("pandas")
    at = pd.to_datetime([0, 86400, 2 * 86400, 0, 86400], unit="s", utc=True)
    return pd.DataFrame(
        {
            "machine": ["a", "a", "a", "b", "b"],
            "recorded_at": at,
            "status": ["ok", "ok", "ok", "ok", "failed"],
            "valid": [True, True, False, True, None],
            "k1": [1000.0, 1010.0, 900.0, 2000.0, np.nan],
            "sigma_k1": [5.0, 6.0, 50.0, 8.0, np.nan],
            "k2": [700.0, 650.0, 600.0, 1500.0, np.nan],
            "sigma_k2": [3.0, 4.0, 40.0, 9.0, np.nan],
            "effect": ["linear", "linear", "coulomb_friction", "linear", None],
        }
    )


def test_batch_histories_draw_the_valid_springs_with_their_sigmas(fleet_table):
    from matplotlib.dates import date2num

    from algid.plotting.batch import histories_figure

    fig = histories_figure(fleet_table)
    valid = {"a": [0, 1], "b": [3]}  # the third row of "a" is not valid, the last failed
    for ax, machine in zip(fig.axes, ("a", "b")):
        rows = fleet_table.loc[valid[machine]]
        for container, k in zip(ax.containers, ("k1", "k2")):
            line, _, (bars,) = container
            np.testing.assert_allclose(date2num(line.get_xdata()), date2num(rows["recorded_at"].dt.tz_localize(None)))
            np.testing.assert_allclose(np.asarray(line.get_ydata(), float), rows[k].to_numpy(float))
            ends = np.array([[seg[0, 1], seg[1, 1]] for seg in bars.get_segments()])
            np.testing.assert_allclose(
                np.sort(ends, axis=1), np.c_[rows[k] - rows[f"sigma_{k}"], rows[k] + rows[f"sigma_{k}"]].astype(float)
            )
        assert _inside(ax, rows[["k1", "k2"]].to_numpy(float))


def test_batch_verdicts_count_the_outcomes(fleet_table):
    from algid.plotting.batch import verdicts_figure

    fig = verdicts_figure(fleet_table)
    ident, diag = fig.axes
    bars = {t.get_text(): p.get_height() for t, p in zip(ident.get_xticklabels(), ident.patches)}
    assert bars == {"failed": 1, "not valid": 1, "valid": 3}
    bars = {t.get_text(): p.get_height() for t, p in zip(diag.get_xticklabels(), diag.patches)}
    assert bars == {"linear": 3, "coulomb_friction": 1}
    assert ident.get_ylim()[1] >= 3


def test_diagnosis_time_plots_draw_the_equation_errors(axis_friction):
    from algid.plotting.diagnosis import fig_prediction, fig_residuals_time

    _, d = axis_friction
    P = d.P
    before, after = d.residuals()
    fig = fig_residuals_time(d)
    for i, ax in enumerate(fig.axes):
        lines = ax.get_lines()
        np.testing.assert_array_equal(lines[0].get_ydata(), before[:, i])
        if d.best is not None:
            np.testing.assert_array_equal(lines[1].get_ydata(), after[:, i])
        rms = np.sqrt(np.mean(before[: P.nw * P.L, i].reshape(P.nw, P.L) ** 2, axis=1))
        np.testing.assert_allclose(lines[-1].get_ydata(), rms)
        np.testing.assert_allclose(np.diff(lines[-1].get_xdata()), P.L * P.dt)
        assert _inside(ax, before[:, i])
    fig = fig_prediction(d)
    for i, ax in enumerate(fig.axes):
        measured, linear = ax.get_lines()[:2]
        t = np.asarray(measured.get_xdata())
        span = np.searchsorted(P.t, t)
        np.testing.assert_allclose(P.t[span], t)
        assert t.size == min(2, P.nw) * P.L  # two whole windows
        gap = np.asarray(measured.get_ydata()) - np.asarray(linear.get_ydata())
        np.testing.assert_allclose(gap, before[span, i], rtol=1e-9, atol=1e-12 * np.abs(before).max())
        assert _inside(ax, measured.get_ydata())


def test_ranking_bars_are_the_withheld_gaps(axis_friction):
    _, d = axis_friction
    fig = fig_ranking(d)
    ax = fig.axes[0]
    gaps = [s.gap_after for s in d.ranking[:12]]
    widths = [p.get_width() for p in ax.patches]
    np.testing.assert_allclose(widths, gaps)
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels[0].startswith(d.ranking[0].fit.effect)
    (linear,) = [line for line in ax.get_lines() if line.get_label().startswith("linear model")]
    assert linear.get_xdata()[0] == pytest.approx(d.gap_before)
    lo, hi = ax.get_xlim()
    assert lo <= min(gaps) and hi >= max(gaps + [d.gap_before])


def test_window_parameters_draw_each_window_fit_over_the_whole_record_fit(axis_friction):
    from algid.diagnosis.locate import window_parameters
    from algid.plotting.diagnosis import fig_window_parameters

    _, d = axis_friction
    wp = window_parameters(d.P, d.lin)
    fig = fig_window_parameters(d)
    for e, ax in enumerate(fig.axes):
        vals = np.array(wp["least_squares"][e]["values"])
        for k, line in enumerate(ax.get_lines()[: vals.shape[1]]):
            np.testing.assert_allclose(line.get_xdata(), wp["t_mid_s"])
            np.testing.assert_allclose(line.get_ydata(), vals[:, k] / d.lin.theta[e][k])
        assert _inside(ax, np.array([1.0]))
