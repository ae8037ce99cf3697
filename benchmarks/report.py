"""Write docs/benchmarks.md from the benchmarks' JSON results (results, tightness, robust_tightness, scale, shapes).

``make bench`` runs it after the benchmarks; ``make docs`` and a test only check that the committed page
matches the JSON files (building the docs never writes a tracked file). Usage: ``python benchmarks/report.py``.
"""

from __future__ import annotations

import ast
import json
from pathlib import Path
from typing import Any

from intervalobs.examples.scale_cases import TANK_SIZES

HERE = Path(__file__).resolve().parent
PAGE = HERE.parent / "docs" / "benchmarks.md"

# Rows of the (68) tightness table: label -> key in tightness.json.
TIGHTNESS_ROWS = {
    "interval observer (framer, paper gain L = [0.3 0.2 0.8])": "interval (framer, paper gain)",
    "zonotopic observer ((26) gain)": "zonotopic ((26) gain)",
    "best intersection (4 framers + paper framer + tube + zonotopic + output contraction)": (
        "intersection: 4 framers + paper framer + tube + zonotopic + contraction"
    ),
    "worst-case-optimal FIR, N = 80, ∩ tube ∩ one-step prediction": "FIR N=80 (worst-case-optimal LP weights) ∩ tube",
}


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, (list, dict)):
        return json.dumps(value)
    return str(value).replace("|", "\\|")


def _table(rows: list[dict[str, Any]]) -> list[str]:
    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(_cell(row.get(c, "")) for c in columns) + " |" for row in rows]
    return lines


def _span(values: list[float]) -> str:
    return f"{min(values):.3f}–{max(values):.3f}"


def _docstring(path: Path) -> str:
    return ast.get_docstring(ast.parse(path.read_text())) or ""


def recursion_section() -> list[str]:
    """The recursion and batching benchmark (benchmarks/run.py)."""
    runner, results = HERE / "run.py", HERE / "results.json"
    lines = [
        "## Recursion and Monte Carlo batching",
        "",
        "`benchmarks/run.py`:",
        "",
        *_docstring(runner).splitlines(),
        "",
    ]
    if not results.exists():
        return [*lines, "No results yet: run `make bench`.", ""]
    data = json.loads(results.read_text())
    lines += ["Results of the last `make bench` (`benchmarks/results.json`):", ""]
    lines += [f"- **{k}**: {_cell(v)}" for k, v in data.items() if not isinstance(v, (list, dict))]
    lines.append("")
    for key, value in data.items():
        if isinstance(value, list) and value and all(isinstance(r, dict) for r in value):
            lines += [f"### {key}", "", *_table(value), ""]
    return lines


def tightness_section() -> list[str]:
    """Width ratios to the exact hull on numerical-3state (68), the learned FIR bank, and LP costs."""
    results = HERE / "tightness.json"
    lines = [
        "## Tightness: width / exact hull width on numerical-3state (68)",
        "",
        *_docstring(HERE / "tightness.py").splitlines(),
        "",
    ]
    if not results.exists():
        return [*lines, "No results yet: run `make bench`.", ""]
    data = json.loads(results.read_text())
    ratios = data["ratios_to_predicted_hull"]
    rows = dict(TIGHTNESS_ROWS)
    rows.update({k: k for k in ratios["iid-vertex"] if k.startswith("FIR bank")})
    lines += [
        "Ranges over seeds 0, 1, 2. *Predicted* hull: data y_0 … y_{k−1}, the information of every observer row;",
        "*filtered* hull: also y_k (the issue's reference measurement). Details: docs/tightness.md.",
        "",
        "| observer | i.i.d. vertex / predicted | / filtered | switching bang-bang / predicted | / filtered |",
        "|---|---|---|---|---|",
    ]
    for label, key in rows.items():
        cells = [
            _span(ratios[kind][key])
            for kind in (
                "iid-vertex",
                "iid-vertex, ratio to the FILTERED hull",
                "extreme",
                "extreme, ratio to the FILTERED hull",
            )
        ]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    hull = "hull (filtered, y_0..y_k): mean width"
    lines += [
        "",
        f"Filtered hull, mean summed width: {_span(ratios['iid-vertex'][hull])} (i.i.d. vertex), "
        f"{_span(ratios['extreme'][hull])} (switching bang-bang).",
        "",
    ]
    if "bank" in data:
        bank = [{"setting": k, **{c: v for c, v in row.items()}} for k, row in data["bank"].items()]
        lines += ["### Learned FIR bank: training, size, cost (i.i.d. vertex noise)", "", *_table(bank), ""]
    costs = [{"quantity": k, "value": v} for k, v in data["costs"].items()]
    lines += ["### Costs (n = 3, 200 steps, shared 2-core machine)", "", *_table(costs), ""]
    return lines


def robust_section() -> list[str]:
    """Tightness under interval ΔA (benchmarks/robust_tightness.py)."""
    results = HERE / "robust_tightness.json"
    lines = ["## Tightness under interval ΔA", "", *_docstring(HERE / "robust_tightness.py").splitlines(), ""]
    if not results.exists():
        return [*lines, "No results yet: run `make bench`.", ""]
    data = json.loads(results.read_text())
    lines += [
        "Ranges over seeds 0, 1, 2 (widths: mean summed width over the steps where the lower bound is computed).",
        "",
        "| example | true ΔA | lower bound | RobustHullEstimator | / lower bound "
        "| RobustFiniteMemoryObserver / lower bound | IntervalObserver / lower bound "
        "| IntersectionObserver / lower bound | enclosure RobustHull / RobustFIR | RobustHull ms/step "
        "| RobustFIR ms/step | IntervalObserver ms/step | lower bound s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, per in data.items():
        for key in ("ΔA at a vertex", "ΔA at a random point"):
            if key not in per:
                continue
            runs = list(per[key].values())

            def span(field: str, runs: list[dict[str, Any]] = runs) -> str:
                return _span([float(r[field]) for r in runs])

            cells = [
                span("lower bound"),
                span("RobustHullEstimator"),
                span("ratio"),
                span("RobustFiniteMemoryObserver ratio"),
                span("IntervalObserver ratio"),
                span("IntersectionObserver ratio"),
                f"{min(r['enclosure'] for r in runs):.3f} / "
                f"{min(r['RobustFiniteMemoryObserver enclosure'] for r in runs):.3f}",
                span("RobustHullEstimator ms/step"),
                span("RobustFiniteMemoryObserver ms/step"),
                span("IntervalObserver ms/step"),
                span("lower bound s"),
            ]
            label = f"{name} (H = {per['horizon']}, N = {per['fir window']})"
            lines.append(f"| {label} | {key[6:]} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "Per seed (0 / 1 / 2): the ratios to the lower bound against issue 19's targets (numerical-3state ≤ 1.3, "
        "two-tank ≤ 2, spring-mass-lti ≤ 3).",
        "",
        "| example | true ΔA | lower bound | RobustHullEstimator | RobustFiniteMemoryObserver | IntervalObserver |",
        "|---|---|---|---|---|---|",
    ]
    for name, per in data.items():
        for key in ("ΔA at a vertex", "ΔA at a random point"):
            runs = list(per.get(key, {}).values())
            if runs:
                fields = ("lower bound", "ratio", "RobustFiniteMemoryObserver ratio", "IntervalObserver ratio")
                cells = [" / ".join(f"{float(r[f]):.3f}" for r in runs) for f in fields]
                lines.append(f"| {name} | {key[6:]} | " + " | ".join(cells) + " |")
    mccormick, notes = "RobustHullEstimator McCormick", []
    for name, per in data.items():
        for key in ("ΔA at a vertex", "ΔA at a random point"):
            runs = list(per.get(key, {}).values())
            if runs and all(f"{mccormick} ratio" in r for r in runs):
                ratios = " / ".join(f"{float(r[f'{mccormick} ratio']):.3f}" for r in runs)
                cost = _span([float(r[f"{mccormick} ms/step"]) for r in runs])
                worst = max(float(r[f"{mccormick} max violation"]) for r in runs)
                notes.append(
                    f"- {name}, {key[6:]}: McCormick window LP (H = {per['mccormick horizon']}) / lower bound "
                    f"{ratios}, {cost} ms/step, largest violation of the truth {worst:g}."
                )
    lines += ["", *notes, ""] if notes else [""]
    return [*lines, *lp_free_rows(data), ""]


def lp_free_rows(data: dict[str, Any]) -> list[str]:
    """Per seed: width, ratio, cost and enclosure of every learned RobustFiniteMemoryObserver bank."""
    fir = "RobustFiniteMemoryObserver"
    lines = [
        f"LP-free {fir} per seed (0 / 1 / 2): the bank of all learned filters and, where the example sets "
        '"fir size", a random subset of them (issue 19: an LP-free variant at ≤ 1 ms/step on (68)). '
        "Enclosure: the smallest fraction of the truth's samples inside over the seeds; lower bound inside: "
        "in every box of the seeds.",
        "",
        "| example | bank (filters per component) | true ΔA | width | / lower bound | ms/step | enclosure "
        "| lower bound inside |",
        "|---|---|---|---|---|---|---|---|",
    ]
    notes = []
    for name, per in data.items():
        labels = [k[: -len(" learn s")] for k in per if k.startswith(fir) and k.endswith(" learn s")]
        for label in labels:
            kind = "all filters"
            if label != fir:
                kind = f"learn(size={per['fir size']}, selection={per.get('fir selection', 'random')!r})"
            bank = f"{kind} ({per[f'{label} filters per component']})"
            for key in ("ΔA at a vertex", "ΔA at a random point"):
                runs = list(per.get(key, {}).values())
                if not runs:
                    continue
                cells = [" / ".join(f"{float(r[f]):.3f}" for r in runs) for f in (label, f"{label} ratio")]
                cells += [
                    " / ".join(f"{float(r[f'{label} ms/step']):.2f}" for r in runs),
                    f"{min(float(r[f'{label} enclosure']) for r in runs):.3f}",
                    "yes" if all(r[f"{label} lower bound inside"] for r in runs) else "NO",
                ]
                lines.append(f"| {name} | {bank} | {key[6:]} | " + " | ".join(cells) + " |")
        learned = ", ".join(f"{per[f'{label} learn s']:.3g} s" for label in labels)
        clock = per.get("clock", "wall clock")
        notes.append(f"- {name}: learned in {learned} (in the order of the table); costs per step: {clock}.")
    return [*lines, "", *notes]


def scale_section() -> list[str]:
    """Cost against size on the tank cascades (benchmarks/scale.py), with the issue's targets checked."""
    results = HERE / "scale.json"
    lines = ["## Cost against size: tank cascades", "", *_docstring(HERE / "scale.py").splitlines(), ""]
    if not results.exists():
        return [*lines, "No results yet: run `make bench`.", ""]
    data = json.loads(results.read_text())
    rows = {row["n"]: row for row in data["rows"]}
    lines += [f"Settings: {_cell(data['settings'])}.", "", *_table(data["rows"]), ""]
    missing = [n for n in TANK_SIZES if n not in rows]
    if missing:
        lines += [
            f"Not measured in this run: n = {', '.join(map(str, missing))} (the run was stopped before these sizes; "
            "`python benchmarks/scale.py` measures every size and caps a cell by its budget).",
            "",
        ]
    targets = [
        ("hull ≤ 5 ms/step at n ≤ 6", [rows.get(3, {}).get("hull ms/step"), rows.get(6, {}).get("hull ms/step")], 5.0),
        ("hull ≤ 50 ms/step at n = 30, p = 21", [rows.get(30, {}).get("hull ms/step")], 50.0),
        ("bank ≤ 1 ms/step at n = 30", [rows.get(30, {}).get("bank ms/step")], 1.0),
        ("learn ≤ 60 s at n = 30", [rows.get(30, {}).get("bank learn s")], 60.0),
        ("bank within 1.1× of the window hull", [row.get("bank / hull") for row in rows.values()], 1.1),
        (
            f"hull within 1.02× of the exact hull (first {data['settings'].get('exact_steps')} steps)",
            [row["hull / exact"] for row in rows.values() if "hull / exact" in row],
            1.02,
        ),
        (
            "filtered hull rows ≤ 1.3× the predicted rows' cost (issue 36)",
            [row.get("filtered / predicted cost") for row in rows.values()],
            1.3,
        ),
    ]
    lines += ["Targets of issues 21 and 36 on these runs:", ""]
    for label, values, limit in targets:
        numbers = [v for v in values if isinstance(v, float)]
        if not values or len(numbers) < len(values):
            verdict = "not measured (see the table)"
        else:
            verdict = ("met" if max(numbers) <= limit else "NOT met") + f" ({', '.join(f'{v:.4g}' for v in numbers)})"
        lines.append(f"- {label}: {verdict}")
    return [*lines, ""]


def _range(values: list[Any], spec: str) -> str:
    """``min–max`` of ``values`` in format ``spec`` (one number when they print alike)."""
    low, high = f"{min(values):{spec}}", f"{max(values):{spec}}"
    return low if low == high else f"{low}–{high}"


def shapes_section() -> list[str]:
    """Vehicle, pedestrian and short record against the exact hull (benchmarks/shapes.py), with the issue's verdicts."""
    results = HERE / "shapes.json"
    lines = ["## Other shapes: width against the exact hull", "", *_docstring(HERE / "shapes.py").splitlines(), ""]
    if not results.exists():
        return [*lines, "No results yet: run `make bench`.", ""]
    data = json.loads(results.read_text())
    cases: dict[str, list[dict[str, Any]]] = {}
    for row in data["rows"]:
        cases.setdefault(row["case"], []).append(row)
    columns = {  # field -> (heading, format)
        "exact hull s": ("exact hull s", ".3g"),
        "hull ms/step": (f"hull H = {data['settings']['H']} ms/step", ".3g"),
        "hull / exact": ("hull / exact", ".5f"),
        "bank learn s": ("bank learn s", ".3g"),
        "bank filters": ("bank filters", "d"),
        "bank ms/step": ("bank ms/step", ".3g"),
        "bank / exact": ("bank / exact", ".4f"),
        "tube design s": ("tube design s", ".3g"),
        "tube ms/step": ("tube ms/step", ".3g"),
        "tube / exact": ("tube / exact", ".3f"),
        "inside": ("inside", ".2g"),
    }
    seeds = ", ".join(str(s) for s in data["settings"]["seeds"])
    lines += [
        f"Settings: {_cell(data['settings'])}. Ranges over the seeds {seeds} (min–max).",
        "",
        "| case (n, p, m, noise generators) | steps (widths from) | "
        + " | ".join(heading for heading, _ in columns.values())
        + " |",
        "|" + "---|" * (len(columns) + 2),
    ]
    for name, runs in cases.items():
        first = runs[0]
        shape = f"{name} ({first['n']}, {first['p']}, {first['m']}, {first['noise generators']})"
        cells = [_range([r[field] for r in runs], spec) for field, (_, spec) in columns.items()]
        lines.append(f"| {shape} | {first['steps']} ({first['widths from step']}) | " + " | ".join(cells) + " |")
    verdicts = [
        ("bank within 1.1× of the exact hull", "bank / exact", 1.1, ".4f"),
        (f"hull (H = {data['settings']['H']}) within 1.02× of the exact hull", "hull / exact", 1.02, ".5f"),
        ("hull ≤ 5 ms/step (n ≤ 6)", "hull ms/step", 5.0, ".3g"),
    ]
    lines += ["", "Targets of issue 21 on these runs (the worst seed in parentheses):", ""]
    for label, field, limit, spec in verdicts:
        worst = {name: max(r[field] for r in runs) for name, runs in cases.items()}
        parts = [f"{name} {'yes' if value <= limit else 'NO'} ({value:{spec}})" for name, value in worst.items()]
        lines.append(f"- {label}: " + ", ".join(parts))
    return [*lines, ""]


def campaign_section() -> list[str]:
    """Task cost, measured and modelled parallel efficiency of the manipulator campaign (campaign_scaling.py)."""
    results = HERE / "campaign_scaling.json"
    lines = ["## Campaign scaling", "", *_docstring(HERE / "campaign_scaling.py").splitlines(), ""]
    if not results.exists():
        return [*lines, "No results yet: run `python benchmarks/campaign_scaling.py`.", ""]
    data = json.loads(results.read_text())
    cost = data["task_cost"]
    lines += [
        f"On {data['cores']} cores: one task costs {cost['fixed_s']:.3g} s fixed + {cost['per_run_s']:.3g} s a run, "
        f"a level's model {cost['level_s']:.3g} s, a fresh worker's start {cost['start_s']:.3g} s (CPU, one "
        f"process). Measured ({_cell(data['measured']['runs'])} "
        f"runs a cell, magnitudes {_cell(data['measured']['magnitudes'])}, one level):",
        "",
        *_table(data["measured"]["rows"]),
        "",
    ]
    loads = [row.get("load_1min", 0.0) for row in data["measured"]["rows"]]
    if max(loads) >= data["cores"]:
        lines += [
            f"Not a valid measurement: the load average was {min(loads):.3g}–{max(loads):.3g} on {data['cores']} "
            "cores, so these rows measure the other work on the machine as much as the campaign.",
            "",
        ]
    for runs, rows in data["modelled_paper_grid"]["rows_by_runs_a_cell"].items():
        lines += [f"Modelled, paper grid with {runs} runs a cell:", "", *_table(rows), ""]
    return [*lines, f"Note: {data['note']}.", ""]


def nonlinear_section() -> list[str]:
    """Width ratios of the continuous-time nonlinear estimators to a consistent-set inner hull
    (nonlinear_tightness.py)."""
    results = HERE / "nonlinear_tightness.json"
    lines = ["## Continuous-time nonlinear cases", "", *_docstring(HERE / "nonlinear_tightness.py").splitlines(), ""]
    if not results.exists():
        return [*lines, "No results yet: run `python benchmarks/nonlinear_tightness.py`.", ""]
    data = json.loads(results.read_text())
    rows = [
        {
            "case": name,
            "estimator": estimator,
            "ratio per state": " / ".join(f"{value:.3g}" for value in facts["ratio"]),
            "enclosure": facts["enclosure"],
            "CPU ms per sample": round(facts["ms_per_sample"], 3),
        }
        for name, case in data["cases"].items()
        for estimator, facts in case["estimators"].items()
    ]
    return [*lines, *_table(rows), ""]


def render() -> str:
    """The whole page.

    Returns
    -------
    str
    """
    lines = ["# Benchmarks", "", "`make bench` runs the benchmarks below and rewrites this page.", ""]
    return (
        "\n".join(
            [
                *lines,
                *recursion_section(),
                *tightness_section(),
                *robust_section(),
                *scale_section(),
                *shapes_section(),
                *campaign_section(),
                *nonlinear_section(),
            ]
        ).rstrip("\n")
        + "\n"
    )


def main() -> None:
    """Write docs/benchmarks.md."""
    text = render()
    if not PAGE.exists() or PAGE.read_text() != text:  # unchanged pages keep their time stamp (Sphinx)
        PAGE.write_text(text)
    print(f"written {PAGE}")


if __name__ == "__main__":
    main()
