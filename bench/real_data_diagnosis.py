"""``algid diagnose`` on the measured data sets of ``../shared/data`` (issue 6).

Reproduces the numbers and figures of ``docs/real_data.md``:

* Silverbox (electronic Duffing oscillator): input V1 as force, output V2 as
  displacement (the acceleration is derived by :func:`algid.recording.accelerations`),
  one DOF; the arrow (first 40 000 samples, amplitude growing), the multisine part and
  the whole record.
* F-16 ground vibration test: (a) the three accelerometers as a 3-DOF chain
  [shaker point, wing side of the joint, payload side], force on DOF 1 only, free right
  end, at excitation levels 1 and 7 (full multisine); (b) the wing-side accelerometer and
  the force band-passed around the wing-torsion mode (6.5-8.2 Hz, 4th-order Butterworth,
  zero phase) as an equivalent one-DOF (modal) system, at levels 1, 3, 5, 7.

Usage::

    python bench/real_data_diagnosis.py [--data ../shared/data] [--figures docs/figures]
        [--json bench/results/real_data.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

from algid.diagnosis import diagnose  # noqa: E402
from algid.diagnosis.report import to_json, to_text  # noqa: E402
from algid.recording.datasets import f16_chain_recording, f16_modal_recording, silverbox_recording  # noqa: E402


def _summary(d) -> dict:
    js = to_json(d)
    keep = (
        "effect",
        "location",
        "params",
        "params_std",
        "gap_before",
        "gap_after",
        "gap_before_fullband",
        "gap_after_fullband",
        "gap_before_force",
        "gap_after_force",
        "band",
        "linear_model",
        "analysis",
        "model",
        "equation_form",
        "combination",
        "mains_hum_removed_hz",
    )
    out = {k: js[k] for k in keep}
    out["ranking_top3"] = [
        {k: r[k] for k in ("effect", "location", "params", "gap_after", "gap_after_fullband", "z_noise")}
        for r in js["ranking"][:3]
    ]
    out["where"] = {
        "per_dof": js["where"]["per_dof"],
        "frequency": js["where"]["frequency"],
        "amplitude": js["where"]["amplitude"],
    }
    out["wall_s"] = d.timings.get("total")
    return out


def level_figure(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lv = [r["level"] for r in rows]
    f = [r["natural_hz"] for r in rows]
    zeta = [r["damping_ratio"] for r in rows]
    gb = [r["gap_before"] for r in rows]
    fig, ax = plt.subplots(1, 3, figsize=(10, 3.0))
    ax[0].plot(lv, f, "o-")
    ax[0].set_ylabel("natural frequency [Hz]")
    ax[1].plot(lv, np.array(zeta) * 100, "o-", color="C3")
    ax[1].set_ylabel("damping ratio [%]")
    ax[2].plot(lv, gb, "o-", color="C2")
    ax[2].set_ylabel("withheld in-band gap, linear model")
    for a in ax:
        a.set_xlabel("excitation level")
        a.grid(alpha=0.3)
    fig.suptitle("F-16, wing side of the joint, torsion mode (6.5-8.2 Hz band): linear fit per level", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=ROOT.parent / "shared" / "data")
    ap.add_argument("--figures", type=Path, default=ROOT / "docs" / "figures")
    ap.add_argument("--json", type=Path, default=ROOT / "bench" / "results" / "real_data.json")
    args = ap.parse_args(argv)
    from algid.plotting.diagnosis import save_figures

    args.figures.mkdir(parents=True, exist_ok=True)
    out: dict = {"silverbox": {}, "f16_chain": {}, "f16_modal": []}
    for part in ("arrow", "multisine", "all"):
        t0 = time.perf_counter()
        d = diagnose(silverbox_recording(args.data, part))
        print(to_text(d, f"Silverbox SNLS80mV, {part}"), "\n")
        out["silverbox"][part] = _summary(d)
        if part == "arrow":
            for path in save_figures(
                d, args.figures / "_tmp", which=("restoring_force.png", "residuals_spectrum.png", "ranking.png")
            ):
                path.replace(args.figures / f"silverbox_{path.name}")
        print(f"[{time.perf_counter() - t0:.1f} s]", file=sys.stderr)
    for level in (1, 7):
        d = diagnose(f16_chain_recording(args.data, level), boundary="free")
        print(to_text(d, f"F-16 FullMSine level {level}, 3-DOF chain"), "\n")
        out["f16_chain"][f"level{level}"] = _summary(d)
        if level == 7:
            for path in save_figures(d, args.figures / "_tmp", which=("residuals_spectrum.png", "ranking.png")):
                path.replace(args.figures / f"f16_chain_L7_{path.name}")
    rows = []
    for level in (1, 3, 5, 7):
        d = diagnose(f16_modal_recording(args.data, level))
        print(to_text(d, f"F-16 FullMSine level {level}, torsion band, 1 DOF"), "\n")
        m, c, k = d.lin.theta[0]
        s = _summary(d)
        s.update(
            level=level, natural_hz=float(np.sqrt(k / m) / (2 * np.pi)), damping_ratio=float(c / (2 * np.sqrt(k * m)))
        )
        rows.append(s)
    out["f16_modal"] = rows
    level_figure(rows, args.figures / "f16_modal_levels.png")
    tmp = args.figures / "_tmp"
    if tmp.exists():
        for f in tmp.iterdir():
            f.unlink()
        tmp.rmdir()
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(out, indent=1))
    print(f"wrote {args.json} and figures in {args.figures}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
