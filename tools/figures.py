"""The measured figures of the docs, built from ``bench/results/*.json``.

A page holds a generated block between two markers::

    <!-- figures:NAME -->

    ... (written by this script: do not edit by hand) ...

    <!-- /figures:NAME -->

``BLOCKS[NAME]`` builds the block's Markdown from the result files. Re-measuring a figure is
re-running its benchmark (``bench/README.md`` gives the command that writes each result
file) and then ``python tools/figures.py --write``; no source file changes.

    python tools/figures.py            check: exit 1 and name every block that differs
    python tools/figures.py --write    rewrite the blocks in place

``tests/test_docs_figures.py`` runs the check.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "bench" / "results"
DOCS = ROOT / "docs"
BLOCK = re.compile(r"(<!-- figures:(?P<name>[\w-]+) -->\n)(?P<body>.*?)(<!-- /figures:(?P=name) -->)", re.S)


@cache
def result(name: str) -> dict:
    """The result file ``bench/results/NAME.json``."""
    return json.loads((RESULTS / f"{name}.json").read_text())


# -- formatting ---------------------------------------------------------------------------


def pct(x: float, digits: int = 2) -> str:
    """A ratio as a percentage with ``digits`` significant digits: 0.00340 -> '0.34'."""
    return f"{100 * x:#.{digits}g}".rstrip(".")


def span(values, fmt) -> str:
    """'a-b' of the smallest and largest value (one value when they print alike)."""
    lo, hi = fmt(min(values)), fmt(max(values))
    return lo if lo == hi else f"{lo}-{hi}"


def num(x: float, digits: int = 2) -> str:
    """A number with ``digits`` significant digits, trailing zeros kept: 2.0128 -> '2.0'."""
    return f"{x:#.{digits}g}".rstrip(".")


def sec(x: float) -> str:
    """A time [s] to the millisecond, trailing zeros dropped: 0.480 -> '0.48'."""
    return f"{x:.3f}".rstrip("0").rstrip(".")


def table(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in rows]) + "\n"


# -- docs/demo.md -------------------------------------------------------------------------


def demo_runs(prefix: str) -> list[dict]:
    """Headlines of the demo report's scenarios ``PREFIX_seed*``."""
    sc = result("demo_report")["scenarios"]
    return [v["headline"] for k, v in sc.items() if re.fullmatch(rf"{prefix}_seed\d+", k)]


def rig_runs(pattern: str) -> list[dict]:
    """The rig rows of the demo report whose name matches ``pattern``."""
    return [v for k, v in result("demo_report")["rig"].items() if re.fullmatch(pattern, k)]


def demo_table() -> str:
    """The demo's runs: when the estimates settle, how far off they stay, how well it tracks."""
    sc = result("demo_report")["scenarios"]
    paper = sc["continuous_noise_free"]["headline"]
    cont, samp = demo_runs("continuous_40dB"), demo_runs("sampled_40dB")
    rig0, rig40 = rig_runs(r"sampled_lag\dms_noise_free"), rig_runs(r"sampled_lag\dms_40dB_seed\d")
    wrong = rig_runs(r"sampled_lag5ms_told\dms_noise_free")
    peak = "peak_tracking_after_1s_pct_stroke"
    by_lag = ", ".join(
        f"{pct(r['max_rel_err_from_0.1s'])} % at {lag} ms" for lag, r in zip((0, 2, 5), rig0, strict=True)
    )
    rows = [
        [
            "`algid demo` (continuous-time control, noise-free)",
            f"{sec(paper['all_first_within_1pct_s'])} s; "
            f"all stay within 1 % from {sec(paper['all_stay_within_1pct_s'])} s",
            f"{num(paper[peak])} % of the 5 mm stroke",
        ],
        [
            f"`--noise-db 40` (continuous estimator, {len(cont)} seeds)",
            f"substituted at {span([r['estimates_substituted_s'] for r in cont], sec)} s; "
            f"largest error at 5 s {span([r['max_rel_err_at_end'] for r in cont], pct)} %",
            f"{span([r[peak] for r in cont], num)} %",
        ],
        [
            f"`--mode sampled --noise-db 40` ({len(samp)} seeds, position feedback)",
            f"all stay within 1 % from {span([r['all_stay_within_1pct_s'] for r in samp], sec)} s",
            f"{span([r[peak] for r in samp], lambda x: num(x, 3))} %",
        ],
        [
            "rig: `--mode sampled --actuator-lag-ms 0/2/5`, noise-free",
            f"all stay within 1 % from {span([r['all_stay_within_1pct_s'] for r in rig0], sec)} s; "
            f"largest error from 0.1 s on: {by_lag}",
            f"{span([r[peak] for r in rig0], lambda x: num(x, 3))} % (mostly the probe's motion)",
        ],
        [
            f"rig: the same with `--noise-db 40` ({len(rig40)} runs: 3 seeds per lag)",
            f"all stay within 1 % from {span([r['all_stay_within_1pct_s'] for r in rig40], sec)} s; "
            f"largest error after 0.5 s {span([r['max_rel_err_from_0.5s'] for r in rig40], pct)} %",
            f"{span([r[peak] for r in rig40], lambda x: num(x, 3))} %",
        ],
        [
            "rig, 5 ms lag told as 4 or 6 ms (noise-free)",
            f"estimates end {span([r['max_rel_err_from_0.5s'] for r in wrong], pct)} % off",
            f"{span([r[peak] for r in wrong], lambda x: num(x, 3))} %",
        ],
    ]
    return table(["run", "estimates (all within 1 % first at, unless said)", "peak tracking error after 1 s"], rows)


def demo_rig() -> str:
    """The rig's substitution and its Cramer-Rao bound at 0.5 s."""
    rig0, rig40 = rig_runs(r"sampled_lag\dms_noise_free"), rig_runs(r"sampled_lag\dms_40dB_seed\d")
    params = result("demo_report")["scenarios"]["sampled_40dB_seed0"]["summary"]["parameters"]
    names = [p["name"] for p in params]
    bounds = [r["bound_at_0.5s"] for r in rig40]
    p_all = 1.0
    for b in bounds:
        p_all *= b["p_all_within_1pct_if_efficient"]

    once = float(f"{1 / p_all:.1g}")

    def bound(name: str) -> str:
        return span([b["crlb_rel"][names.index(name)] for b in bounds], pct)

    return (
        f"The substitution disturbs the estimates by "
        f"{span([r['substitution_estimate_disturbance'] for r in rig0], pct)} % noise-free "
        f"and by at most {pct(max(r['substitution_estimate_disturbance'] for r in rig40), 2)} % at 40 dB, "
        f"where the law waits for the running estimate "
        f"(substituted at {span([r['estimates_substituted_s'] for r in rig40], sec)} s). "
        f"The Cramer-Rao bound of these runs at 0.5 s is {bound('c3')} % on `c_3` and {bound('c2')} % "
        f"on `c_2`, so an efficient unbiased estimator would have all {len(names)} estimates within "
        f"1 % at 0.5 s in only {span([b['p_all_within_1pct_if_efficient'] for b in bounds], lambda x: pct(x))} % "
        f"of the runs, and in all {len(bounds)} runs about once in {once:g}.\n"
    )


def demo_controller() -> str:
    """The controller's choices against their alternatives, in the same demo report."""
    sc = result("demo_report")["scenarios"]
    peak = "peak_tracking_after_1s_pct_stroke"
    cont = demo_runs("continuous_40dB")
    return table(
        ["choice (Table 1, 5 s)", "peak tracking error after 1 s [% of the stroke]", "alternative"],
        [
            [
                'eq. 10 with the stiffness estimates inside the integrals (`eq10="integrated"`), noise-free',
                num(sc["continuous_noise_free"]["headline"][peak]),
                f"{num(sc['continuous_noise_free_eq10_product']['headline'][peak], 3)} with the paper's product form "
                '(`eq10="product"`)',
            ],
            [
                f'the continuous estimator under `accept="sigma"`, 40 dB with the probe ({len(cont)} seeds)',
                span([r[peak] for r in cont], num),
                f"{num(sc['continuous_40dB_seed0_single_estimator']['headline'][peak], 3)} with the single growing "
                "window in the same loop (seed 0)",
            ],
        ],
    )


# -- docs/performance.md ------------------------------------------------------------------


def ns(config: str, n: int) -> float:
    """Median ns per DOF-sample of a per_sample configuration at ``n`` DOF."""
    return result("per_sample")["configurations"][config][str(n)]["ns_per_dof_sample_median"]


def per_sample_header() -> str:
    """The run the per-sample table comes from."""
    meta = result("per_sample")["meta"]
    load = meta["loadavg_before"] + meta["loadavg_after"]
    return (
        f"`bench/results/per_sample.json` (`{meta['command']}`, {meta['rounds']} rounds), commit "
        f"{meta['machine']['commit']}, {meta['machine']['nproc']} vCPUs of an {meta['machine']['model_name']} "
        f"(AVX-512: {'yes' if meta['machine']['avx512f'] else 'no'}); load average "
        f"{span(load, lambda x: f'{x:.1f}')} during the run (other jobs on the machine), so single medians "
        "move by 5-10 % between rounds. ns per DOF-sample, median.\n"
    )


def per_sample_table() -> str:
    """The per-sample cost against its targets."""
    d = result("per_sample")
    sizes = (1, 3, 10, 50)
    rt = d["runtime_over_fixed"]
    upd = {k: v for k, v in rt.items() if k.startswith("update")}
    worst_key, worst_n = max(((k, n) for k, v in upd.items() for n in v), key=lambda kn: upd[kn[0]][kn[1]])
    py = [v for k, v in rt.items() if k.startswith("python_run") for v in v.values()]
    cpp = d["targets"]["python_run_within_1.5x_of_cpp"]
    path = [c["max_path"] / c["ns_per_dof_sample_median"] for c in d["configurations"]["default_double"].values()]
    numpy = d["numpy_reference_over_python_run_interleaved"]
    at_1khz = [r for r in d["single_precision"] if r["rate_hz"] == 1000]
    flt = {(r["source"], r["scalar"]): r["max_rel_error_at"]["0.10"] for r in at_1khz}
    flops = d["flops"]["per_dof_sample"]
    x = lambda v: f"{v:.2f}"  # noqa: E731
    rows = [
        [
            "`update()`, n = 3, double, portable flags",
            "<= 100",
            f"{ns('default_double', 3):.1f} (x86-64-v3 {ns('default_double_v3', 3):.1f}, "
            f"x86-64-v4 {ns('default_double_v4', 3):.1f})",
        ],
        [
            "per DOF at n = 1 / 3 / 10 / 50, `update()`, portable",
            "n = 50 <= n = 3",
            " / ".join(f"{ns('default_double', n):.1f}" for n in sizes),
        ],
        [
            "run-time sized / fixed-size at the same n, `update()` (n = 1, 3, 10, 50; double and float; every build)",
            "<= 1.5x",
            f"{span([v for r in upd.values() for v in r.values()], x)}x (worst: {worst_key.split('_')[1]}, "
            f"{'x86-64-' + worst_key.split('_')[2] if worst_key.count('_') == 2 else 'portable'}, n = {worst_n})",
        ],
        ["the same, Python `run()`", "<= 1.5x", span(py, x) + "x"],
        [
            f"Python `run()` / the C++ `record()` it calls ({cpp['3']['isa']})",
            "<= 1.5x",
            span([v["ratio"] for v in cpp.values()], x) + "x",
        ],
        ["slowest code path / median (`max_path`), portable", "<= 5x", span(path, x) + "x"],
        [
            "numpy reference / Python `run()`, back to back",
            ">= 50x",
            " / ".join(f"{numpy[str(n)]['ratio_median']:.0f}x" for n in sizes) + " at n = 1 / 3 / 10 / 50",
        ],
        [
            "float, Table 1, t0 + 0.1 s, 1 kHz",
            "< 1 %",
            f"{flt['closed_form', 'float']:.2g} (closed form), {flt['rk4', 'float']:.2g} (RK4 plant)",
        ],
        [
            "flops per DOF-sample (counted)",
            "",
            " / ".join(f"{flops[str(n)]['flops_per_dof_sample']:.0f}" for n in sizes) + " at n = 1 / 3 / 10 / 50",
        ],
    ]
    return per_sample_header() + "\n" + table(["figure", "target", "measured"], rows)


# -- docs/identify.md ---------------------------------------------------------------------


def identify_noisy() -> str:
    """Worst relative error per family on the noisy records, against the paper's single window."""
    acc = result("identify")["accuracy"]
    names = {"table1": "Table 1", "random5": "random 5-DOF", "free3": "free end, 3 DOF"}
    rows = [
        [names[k]]
        + [f"{pct(v['median_worst'][f])} %" for f in "mck"]
        + [" / ".join(f"{100 * v['median_worst_single_window'][f]:.0f} %" for f in "mck")]
        for k, v in acc.items()
    ]
    return table(["system", "m", "c", "k", "the paper's single window on the same records (m / c / k)"], rows)


# -- docs/diagnosis.md --------------------------------------------------------------------


def realistic_blind() -> str:
    """The realistic blind check against its targets."""
    s = result("realistic_blind")["summary"]
    rigs = ", ".join(f"{k} {pct(v['top1_accuracy'], 3)} %" for k, v in s["per_rig"].items())
    rows = [
        ["top-1 effect accuracy", ">= 90 %", f"**{pct(s['top1_accuracy'], 3)} %** ({rigs})"],
        ["location among correct effects", ">= 90 %", f"**{pct(s['location_accuracy_among_correct'], 3)} %**"],
        ["main parameter within 20 %", ">= 80 %", f"**{pct(s['param_within_20pct_among_correct'], 3)} %**"],
        ["median in-band gap shrink, effect cases", ">= 3x", f"**{s['median_gap_shrink_real']:.3g}x**"],
        ["`none` on a case with an effect", "<= 5 %", f"**{pct(s['false_none_on_effect'], 2)} %**"],
        ["`none` on an inadmissible linear fit", "0 %", f"**{pct(s['none_on_inadmissible'], 1)} %**"],
        ["false alarms on `none` cases", "-", f"{pct(s['false_alarm_rate_none'], 1)} %"],
        ["time per record", "-", f"median {s['wall_s_median']:.2f} s, at most {s['wall_s_max']:.2g} s"],
    ]
    first, end = result("realistic_blind")["seeds"].split(":")
    seeds = f"{first}-{int(end) - 1}"
    return table(["figure", "target", f"seeds {seeds} ({s['cases']} cases)"], rows)


def blind_diagnosis() -> str:
    """The blind check of generated cases in one sentence."""
    d = result("blind_diagnosis")
    s = d["summary"]
    return (
        f"top-1 {pct(s['top1_accuracy'], 3)} %, location {pct(s['location_accuracy_among_correct'], 3)} %, "
        f"main parameter within 20 % in {pct(s['param_within_20pct_among_correct'], 3)} %, median in-band "
        f"gap shrink {s['median_gap_shrink_real']:.3g}x (full band {num(s['median_gap_shrink_real_fullband'])}x), "
        f"{'no' if s['false_alarm_rate_none'] == 0 else pct(s['false_alarm_rate_none'])} false alarm on the "
        f"{s['none_cases']} `none` cases; a {d['timing']['recording']} recording diagnosed in "
        f"{d['timing']['wall_s_median']:.2g} s (median of {len(d['timing']['wall_s'])}).\n"
    )


BLOCKS = {
    "demo-runs": demo_table,
    "demo-rig": demo_rig,
    "demo-controller": demo_controller,
    "per-sample": per_sample_table,
    "identify-noisy": identify_noisy,
    "realistic-blind": realistic_blind,
    "blind-diagnosis": blind_diagnosis,
}


def fill(text: str, where: str) -> str:
    """The page ``text`` with every block rebuilt from the results."""

    def one(m: re.Match) -> str:
        name = m["name"]
        if name not in BLOCKS:
            raise SystemExit(f"{where}: unknown figures block {name!r} (known: {', '.join(BLOCKS)})")
        return m.group(1) + "\n" + BLOCKS[name]() + "\n" + m.group(4)

    return BLOCK.sub(one, text)


def stale(write: bool) -> list[str]:
    """The pages whose blocks differ from the results (rewritten when ``write``)."""
    out = []
    for page in sorted(DOCS.rglob("*.md")):
        text = page.read_text()
        new = fill(text, str(page.relative_to(ROOT)))
        if new != text:
            out.append(str(page.relative_to(ROOT)))
            if write:
                page.write_text(new)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", action="store_true", help="rewrite the blocks (default: check only)")
    args = ap.parse_args(argv)
    pages = stale(args.write)
    if pages and not args.write:
        print("figures out of date in: " + ", ".join(pages) + " (run python tools/figures.py --write)")
        return 1
    for p in pages:
        print(f"wrote {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
