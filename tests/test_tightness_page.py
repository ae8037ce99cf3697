"""docs/tightness.md quotes the benchmarks: every such number must be what the benchmark JSON files hold.

The quotes are :class:`paper_notes.Quote` s whose fields are functions of the results of
benchmarks/tightness.py (``"point"``) and benchmarks/robust_tightness.py (``"robust"``). After a
benchmark rerun this test names each sentence of the page to rewrite, as it must read.
Numbers of the page that no benchmark writes are one-off measurements and say so where they stand.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from paper_notes import Quote, number, unquoted

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "tightness.md"

Field = Callable[[Mapping[str, Any]], str]

IID, EXTREME = "iid-vertex", "extreme"
FILTERED = ", ratio to the FILTERED hull"
PRED_HULL, FILT_HULL = "hull (predicted, y_0..y_{k-1}): mean width", "hull (filtered, y_0..y_k): mean width"
INTERVAL, ZONOTOPIC = "interval (framer, paper gain)", "zonotopic ((26) gain)"
CONTRACTION = "intersection: paper framer + output contraction"
FRAMERS = "intersection: 4 framers (coordinates), no contraction"
BEST = "intersection: 4 framers + paper framer + tube + zonotopic + contraction"
BANK = "FIR bank learned from hull certificates (N=10, 6 records) ∩ tube"
FILTERED_BANK = "FIR bank learned from filtered hull certificates (uses y_k; N=10, 6 records)"
N3, TANK, SPRING = "numerical-3state (68)", "two-tank", "spring-mass-lti"
VERTEX, RANDOM = "ΔA at a vertex", "ΔA at a random point"
FIR, SMALL = "RobustFiniteMemoryObserver", "RobustFiniteMemoryObserver small bank"
MCCORMICK = "RobustHullEstimator McCormick"


def results() -> dict[str, Any]:
    """The two benchmarks' JSON results."""
    read = lambda name: json.loads((ROOT / "benchmarks" / name).read_text())  # noqa: E731
    return {"point": read("tightness.json"), "robust": read("robust_tightness.json")}


def span(values: list[float], spec: str = ".2f") -> str:
    """``min–max`` as the page writes it, one number when both read the same."""
    low, high = number(min(values), spec), number(max(values), spec)
    return low if low == high else f"{low}–{high}"


def percent(values: list[float]) -> str:
    """Relative changes (fractions) as ``−a to −b %`` (smallest change first), ``0 %`` when all round to 0."""
    ordered = sorted(values, key=abs)
    low, high = number(100 * ordered[0], ".1f"), number(100 * ordered[-1], ".1f")
    if high in ("0.0", "−0.0"):
        return "0 %"
    return f"{low} %" if low == high else f"{low} to {high} %"


def ratios(kind: str, key: str, spec: str = ".2f") -> Field:
    return lambda d: span(d["point"]["ratios_to_predicted_hull"][kind][key], spec)


def change(kind: str, key: str) -> Field:
    def field(d: Mapping[str, Any]) -> str:
        table = d["point"]["ratios_to_predicted_hull"][kind]
        return percent([a / b - 1 for a, b in zip(table[key], table[INTERVAL])])

    return field


def bank(setting: str, key: str, spec: str) -> Field:
    def field(d: Mapping[str, Any]) -> str:
        value = d["point"]["bank"][setting][key]
        return span(value, spec) if isinstance(value, list) else number(float(value), spec)

    return field


def cost(key: str, spec: str, index: int | None = None, scale: float = 1.0) -> Field:
    def field(d: Mapping[str, Any]) -> str:
        value = d["point"]["costs"][key]
        return number(scale * float(value if index is None else value[index]), spec)

    return field


def constant_width(window: int, spec: str) -> Field:
    """A fixed filter's summed width: its ratio to the predicted hull times that hull (seed 0, i.i.d. vertex)."""
    key = f"FIR N={window} alone (constant width 2·sum radius)"
    return lambda d: number(
        d["point"]["ratios_to_predicted_hull"][IID][key][0] * d["point"]["ratios_to_predicted_hull"][IID][PRED_HULL][0],
        spec,
    )


def floor_ratio(kind: str) -> Field:
    """The largest hull width seen over the mean predicted hull of each run."""

    def field(d: Mapping[str, Any]) -> str:
        table = d["point"]["ratios_to_predicted_hull"]
        sup = table["sup over all runs of the hull width (summed per-component maxima)"]
        return span([sup / w for w in table[kind][PRED_HULL]])

    return field


def runs(d: Mapping[str, Any], example: str, kind: str | None = None) -> list[dict[str, Any]]:
    per = d["robust"][example]
    return [r for k in ((VERTEX, RANDOM) if kind is None else (kind,)) for r in per[k].values()]


def robust(example: str, field: str, spec: str = ".2f", kind: str | None = None) -> Field:
    return lambda d: span([float(r[field]) for r in runs(d, example, kind)], spec)


def seeds(example: str, field: str, kind: str, spec: str = ".3f") -> Field:
    return lambda d: " / ".join(number(float(r[field]), spec) for r in runs(d, example, kind))


def one(example: str, field: str, kind: str, seed: int, spec: str) -> Field:
    return lambda d: number(float(d["robust"][example][kind][f"seed {seed}"][field]), spec)


def relative(example: str, wide: str, narrow: str) -> Field:
    """How much wider ``wide`` is than ``narrow`` over the runs of ``example``, in whole percent."""
    return lambda d: span([100 * (r[wide] / r[narrow] - 1) for r in runs(d, example)], ".0f")


def setting(key: str) -> Field:
    return lambda d: " / ".join(str(d["robust"][e][key]) for e in (N3, TANK, SPRING))


def every_run(d: Mapping[str, Any]) -> list[dict[str, Any]]:
    return [r for e in (N3, TANK, SPRING) for r in runs(d, e)]


def enclosed(d: Mapping[str, Any]) -> str:
    """The smallest enclosure of both estimators over all runs, if the lower bound lies inside every box."""
    rows = every_run(d)
    inside = all(r["lower bound inside"] and r[f"{FIR} lower bound inside"] for r in rows)
    low = min(min(r["enclosure"], r[f"{FIR} enclosure"]) for r in rows)
    return f"{number(low, '.1f')} for both estimators in all {len(rows)} runs" + (
        ", and the lower bound lies inside every box of both"
        if inside
        else ", but the lower bound is NOT always inside"
    )


def costs(field: str, spec: str, examples: tuple[str, ...]) -> Field:
    return lambda d: span([float(r[field]) for e in examples for r in runs(d, e)], spec)


def cost_ratio(d: Mapping[str, Any]) -> str:
    return span([r[f"{MCCORMICK} ms/step"] / r["RobustHullEstimator ms/step"] for r in runs(d, N3)], ".0f")


QUOTES: list[Quote] = [
    Quote(
        "within {v}× of the hull with no LP online",
        {"v": lambda d: number(max(d["point"]["ratios_to_predicted_hull"][IID][BANK]), ".2f")},
    ),
    *(
        Quote(
            f"| {label} | {{hp}} | {{hf}} | {{ip}} | {{if}} | {{zp}} | {{bp}} | {{bf}} | **{{kp}}** | **{{kf}}** |",
            {
                "hp": ratios(kind, PRED_HULL),
                "hf": ratios(kind, FILT_HULL),
                "ip": ratios(kind, INTERVAL),
                "if": ratios(kind + FILTERED, INTERVAL),
                "zp": ratios(kind, ZONOTOPIC),
                "bp": ratios(kind, BEST),
                "bf": ratios(kind + FILTERED, BEST),
                "kp": ratios(kind, BANK),
                "kf": ratios(kind + FILTERED, BANK),
            },
        )
        for label, kind in (("i.i.d. vertices", IID), ('simulator "extreme" (switch prob. 0.1)', EXTREME))
    ),
    Quote(
        "matches the i.i.d.-vertex rows: filtered hull {hf}, predicted/filtered {pf}, interval observer {if}× the "
        "filtered hull",
        {
            "hf": ratios(IID, FILT_HULL),
            "pf": lambda d: span(
                [1 / r for r in d["point"]["ratios_to_predicted_hull"][IID]["filtered hull / predicted hull"]]
            ),
            "if": ratios(IID + FILTERED, INTERVAL),
        },
    ),
    Quote(
        "(`FiniteMemoryObserver.learn`, below): {kf}× the filtered hull and {kp}× the predicted hull",
        {"kf": ratios(IID + FILTERED, BANK), "kp": ratios(IID, BANK)},
    ),
    Quote(
        "online it is a bank of linear filters (≈ {us} µs/step with all {n} filters per component, ≈ {us256} µs/step "
        "with 256 at {r256}×)",
        {
            "us": bank("N=10 records=6 size=all", "run us/step", ".0f"),
            "n": bank("N=10 records=6 size=all", "filters per component", ".0f"),
            "us256": bank("N=10 records=6 size=256", "run us/step", ".0f"),
            "r256": bank("N=10 records=6 size=256", "/ predicted hull", ".2f"),
        },
    ),
    Quote(
        "**{fi}× the filtered hull** under i.i.d. vertex noise, {fe}× under switching bang-bang noise",
        {"fi": ratios(IID + FILTERED, FILTERED_BANK, ".3f"), "fe": ratios(EXTREME + FILTERED, FILTERED_BANK, ".3f")},
    ),
    Quote(
        "| output contraction alone (paper framer) | {i} | {e} | — |",
        {"i": change(IID, CONTRACTION), "e": change(EXTREME, CONTRACTION)},
    ),
    Quote(
        "| 4 framers in the candidate coordinates, restarted from the intersection | {i} | {e} | {t} |",
        {
            "i": change(IID, FRAMERS),
            "e": change(EXTREME, FRAMERS),
            "t": lambda d: percent([r["IntersectionObserver"] / r["IntervalObserver"] - 1 for r in runs(d, TANK)]),
        },
    ),
    Quote(
        "| + paper framer + tube + zonotopic + contraction | {i} | {e} | — |",
        {"i": change(IID, BEST), "e": change(EXTREME, BEST)},
    ),
    Quote(
        "On spring-mass-lti the default `IntersectionObserver.design` is {v}× as wide as `IntervalObserver.design`",
        {"v": lambda d: span([r["IntersectionObserver"] / r["IntervalObserver"] for r in runs(d, SPRING)], ".1f")},
    ),
    *(
        Quote(
            f"| {window} | {{lp}} ms / {{total}} ms | {{w}} | {{ai}} | {{ae}} | {{ci}} | {{ce}} | {{us}} |",
            {
                "lp": cost(f"FIR N={window} design s (total / LPs)", ".0f", 1, 1e3),
                "total": cost(f"FIR N={window} design s (total / LPs)", ".0f", 0, 1e3),
                "w": constant_width(window, spec),
                "ai": ratios(IID, f"FIR N={window} alone (constant width 2·sum radius)"),
                "ae": ratios(EXTREME, f"FIR N={window} alone (constant width 2·sum radius)"),
                "ci": ratios(IID, f"FIR N={window} (worst-case-optimal LP weights) ∩ tube"),
                "ce": ratios(EXTREME, f"FIR N={window} (worst-case-optimal LP weights) ∩ tube"),
                "us": cost(f"FIR N={window} run us/step (incl. tube fallback)", ".0f"),
            },
        )
        for window, spec in ((20, ".2f"), (40, ".2f"), (80, ".3f"))
    ),
    Quote(
        "The largest hull width seen over the six runs, summed over the components' maxima, is {sup}; the N = 80 "
        "filter's summed width is {w80} (within {pct} %), and the tube/framer's steady width is the same {tube}.",
        {
            "sup": lambda d: number(
                d["point"]["ratios_to_predicted_hull"][
                    "sup over all runs of the hull width (summed per-component maxima)"
                ],
                ".3f",
            ),
            "w80": constant_width(80, ".3f"),
            "pct": lambda d: number(
                100
                * (
                    d["point"]["ratios_to_predicted_hull"][IID]["FIR N=80 alone (constant width 2·sum radius)"][0]
                    * d["point"]["ratios_to_predicted_hull"][IID][PRED_HULL][0]
                    / d["point"]["ratios_to_predicted_hull"][
                        "sup over all runs of the hull width (summed per-component maxima)"
                    ]
                    - 1
                ),
                ".1f",
            ),
            "tube": lambda d: number(
                d["point"]["ratios_to_predicted_hull"][IID][INTERVAL][0]
                * d["point"]["ratios_to_predicted_hull"][IID][PRED_HULL][0],
                ".2f",
            ),
        },
    ),
    Quote(
        "≥ {fi}× the mean predicted hull under i.i.d. vertex noise, ≥ {fe}× under the simulator's noise",
        {"fi": floor_ratio(IID), "fe": floor_ratio(EXTREME)},
    ),
    Quote(
        "({ci}× instead of {ii}×;",
        {"ci": ratios(IID, "FIR N=80 (worst-case-optimal LP weights) ∩ tube"), "ii": ratios(IID, INTERVAL)},
    ),
    *(
        Quote(
            f"| {window} | {label} | {{n}} | {{s}} | {{us}} | {{p}} | {{f}} |",
            {
                "n": bank(key, "filters per component", ".0f"),
                "s": bank(key, "learn s", ".2g"),
                "us": bank(key, "run us/step", ".0f"),
                "p": bank(key, "/ predicted hull", ".3f"),
                "f": bank(key, "/ filtered hull", ".2f"),
            },
        )
        for window, label, key in (
            (10, "2", "N=10 records=2 size=all"),
            (10, "6", "N=10 records=6 size=all"),
            (10, "6 (size=256)", "N=10 records=6 size=256"),
            (10, "12", "N=10 records=12 size=all"),
            (20, "6", "N=20 records=6 size=all"),
        )
    ),
    Quote(
        "with R = 2 / 6 / 12 records it holds {a} / {b} / {c} filters per component",
        {
            "a": bank("N=10 records=2 size=all", "filters per component", ".0f"),
            "b": bank("N=10 records=6 size=all", "filters per component", ".0f"),
            "c": bank("N=10 records=12 size=all", "filters per component", ".0f"),
        },
    ),
    Quote(
        "the window hull at H = 10 is itself within {v} of the full-history hull",
        {"v": cost("width ratio H=10 / full", ".3f")},
    ),
    Quote(
        "(one run, switching noise) say {a} / {b} / {c} / {d} ms",
        {
            "a": cost("hull H=10 ms/step", ".3g"),
            "b": cost("hull H=40 ms/step", ".3g"),
            "c": cost("hull H=50 ms/step", ".3g"),
            "d": cost("hull H=full ms/step", ".3g"),
        },
    ),
    Quote('Target "H = 40 within 1.01× of the full hull": met ({v})', {"v": cost("width ratio H=40 / full", ".6f")}),
    Quote(
        "In `benchmarks/tightness.json` (one run each): {e1} / {i1} ms/step with one HiGHS instance, {e2} / {i2} "
        "with `workers=2` (switching / i.i.d. vertex noise).",
        {
            "e1": cost("hull H=40 workers=1 ms/step (extreme)", ".2f"),
            "i1": cost("hull H=40 workers=1 ms/step (iid-vertex)", ".2f"),
            "e2": cost("hull H=40 workers=2 ms/step (extreme)", ".2f"),
            "i2": cost("hull H=40 workers=2 ms/step (iid-vertex)", ".2f"),
        },
    ),
    Quote(
        "Windows: RobustHullEstimator H = {h}, RobustFiniteMemoryObserver N = {n} for numerical-3state / two-tank / "
        "spring-mass-lti",
        {"h": setting("horizon"), "n": setting("fir window")},
    ),
    Quote("Enclosure of the truth {v}.", {"v": enclosed}),
    Quote(
        "**RobustHullEstimator**: spring-mass-lti {s}× and two-tank {t}× are met on every run; numerical-3state is at "
        "{n}× and fails on seed 0 at a vertex only ({n0}×).",
        {
            "s": robust(SPRING, "ratio"),
            "t": robust(TANK, "ratio"),
            "n": robust(N3, "ratio"),
            "n0": one(N3, "ratio", VERTEX, 0, ".3f"),
        },
    ),
    Quote(
        "numerical-3state is at {v}× with ΔA at a vertex ({vs} for seeds 0 / 1 / 2) and {r}× at a random point ({rs}): "
        "**target ≤ 1.3 met on every run**, truth enclosed (largest violation {viol}), the lower bound inside every "
        "box; {ms} ms/step against the split LP's {split} ms/step (H = 40) in the same run",
        {
            "v": robust(N3, f"{MCCORMICK} ratio", ".3f", VERTEX),
            "vs": seeds(N3, f"{MCCORMICK} ratio", VERTEX),
            "r": robust(N3, f"{MCCORMICK} ratio", ".3f", RANDOM),
            "rs": seeds(N3, f"{MCCORMICK} ratio", RANDOM),
            "viol": lambda d: number(max(r[f"{MCCORMICK} max violation"] for r in runs(d, N3)), "g"),
            "ms": robust(N3, f"{MCCORMICK} ms/step", ".0f"),
            "split": robust(N3, "RobustHullEstimator ms/step", ".0f"),
        },
    ),
    Quote(
        "**RobustFiniteMemoryObserver** (LP-free): spring-mass-lti {s}× is met on every run; two-tank {t}× fails on "
        "seed 0 at a vertex ({t0}×) and seed 1 at a random point ({t1}×); numerical-3state {n}× fails on seeds 0 and "
        "1 at a vertex ({n0}×, {n1}×). It is {pn} % wider than the split window LP on numerical-3state, {pt} % on "
        "two-tank and {ps} % on spring-mass-lti",
        {
            "s": robust(SPRING, f"{FIR} ratio"),
            "t": robust(TANK, f"{FIR} ratio"),
            "t0": one(TANK, f"{FIR} ratio", VERTEX, 0, ".3f"),
            "t1": one(TANK, f"{FIR} ratio", RANDOM, 1, ".3f"),
            "n": robust(N3, f"{FIR} ratio"),
            "n0": one(N3, f"{FIR} ratio", VERTEX, 0, ".3f"),
            "n1": one(N3, f"{FIR} ratio", VERTEX, 1, ".3f"),
            "pn": relative(N3, FIR, "RobustHullEstimator"),
            "pt": relative(TANK, FIR, "RobustHullEstimator"),
            "ps": relative(SPRING, FIR, "RobustHullEstimator"),
        },
    ),
    Quote(
        '**A bank of {small} filters per component** on numerical-3state (`learn(size={size}, selection="{sel}")`: '
        "{how} the {n} of the same training) costs {ms} ms/step (CPU time, against {ms_all} ms/step for "
        "all of them) at {v}× the lower bound with ΔA at a vertex and {r}× at a random point (all filters: {v_all} "
        'and {r_all}); enclosure {enc}, the lower bound inside every box. **Target "an LP-free variant at ≤ 1 '
        'ms/step on (68)": {met}** by this bank (not by all filters).',
        {
            "small": lambda d: str(d["robust"][N3][f"{SMALL} filters per component"]),
            "size": lambda d: str(d["robust"][N3]["fir size"]),
            "sel": lambda d: d["robust"][N3].get("fir selection", "random"),
            "how": lambda d: {
                "cover": "the subset that covers the training windows best, of",
                "random": "a random subset of",
            }[d["robust"][N3].get("fir selection", "random")],
            "n": lambda d: str(d["robust"][N3][f"{FIR} filters per component"]),
            "ms": robust(N3, f"{SMALL} ms/step"),
            "ms_all": robust(N3, f"{FIR} ms/step"),
            "v": seeds(N3, f"{SMALL} ratio", VERTEX),
            "r": seeds(N3, f"{SMALL} ratio", RANDOM),
            "v_all": seeds(N3, f"{FIR} ratio", VERTEX),
            "r_all": seeds(N3, f"{FIR} ratio", RANDOM),
            "met": lambda d: "met" if max(r[f"{SMALL} ms/step"] for r in runs(d, N3)) <= 1 else "NOT met",
            "enc": lambda d: (
                number(min(r[f"{SMALL} enclosure"] for r in runs(d, N3)), ".1f")
                + ("" if all(r[f"{SMALL} lower bound inside"] for r in runs(d, N3)) else " (lower bound NOT inside)")
            ),
        },
    ),
    Quote(
        "On numerical-3state (CPU time) the split RobustHullEstimator costs {rh} ms/step and the learned bank "
        "{fir} ms/step; on two-tank and spring-mass-lti (CPU time) {rh_others} and {fir_others} ms/step",
        {
            "rh": costs("RobustHullEstimator ms/step", ".0f", (N3,)),
            "fir": costs(f"{FIR} ms/step", ".1f", (N3,)),
            "rh_others": costs("RobustHullEstimator ms/step", ".0f", (TANK, SPRING)),
            "fir_others": costs(f"{FIR} ms/step", ".1f", (TANK, SPRING)),
        },
    ),
    Quote("its number of filters ({v} per component)", {"v": setting(f"{FIR} filters per component")}),
    Quote(
        "the bound on that run rises to {lb} and the ratio falls from 3.70× to {r}×",
        {"lb": one(TANK, "lower bound", VERTEX, 0, ".2f"), "r": one(TANK, "ratio", VERTEX, 0, ".2f")},
    ),
    Quote(
        "seed 2 at a vertex moves the other way (2.76 → {lb}, ratio 1.19 → {r}:",
        {"lb": one(TANK, "lower bound", VERTEX, 2, ".2f"), "r": one(TANK, "ratio", VERTEX, 2, ".2f")},
    ),
    Quote(
        "the mean from {split} to {mc} ({r}×)",
        {
            "split": one(N3, "RobustHullEstimator", VERTEX, 0, ".2f"),
            "mc": one(N3, MCCORMICK, VERTEX, 0, ".2f"),
            "r": one(N3, f"{MCCORMICK} ratio", VERTEX, 0, ".2f"),
        },
    ),
    Quote("is 2.7 on average (the lower bound {lb})", {"lb": one(N3, "lower bound", VERTEX, 0, ".1f")}),
    Quote("({r}× with H = 20)", {"r": one(N3, f"{MCCORMICK} ratio", VERTEX, 0, ".2f")}),
    Quote("removes most of that (above) at {v}× the cost", {"v": cost_ratio}),
]


def test_every_benchmark_number_of_the_page_is_the_json_s() -> None:
    problems, checked = unquoted(PAGE, QUOTES, results())
    assert problems == [], "\n".join(problems)
    assert checked == len(QUOTES)


def test_ranges_and_changes_are_written_as_on_the_page() -> None:
    assert span([1.0135, 1.0157, 1.0165]) == "1.01–1.02"
    assert span([1.009, 1.0081, 1.0087]) == "1.01"
    assert percent([-0.0112, -0.0082, -0.0102]) == "−0.8 to −1.1 %"
    assert percent([0.0, -0.0, 0.0]) == "0 %"
