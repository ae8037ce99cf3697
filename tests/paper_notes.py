"""The numbers docs/paper-notes.md quotes, each tied to the ``summary.json`` value it must show.

A :class:`Quote` is a piece of the page with ``{name:spec}`` fields; each field's value is a key path
of the reproduction's summary (dot-separated, or a tuple of keys when a key has a dot; list indices as
numbers) or a function of the summary.
A list is written element by element, joined by what follows ``|`` in the spec (default ", ").
Numbers are written as on the page: the minus sign is "−" and exponents have no leading zero (2e-16).
Whitespace is compared collapsed, so a quote may span a line break of the page.

``tests/test_paper_notes.py`` checks the quotes that need no simulation against a fresh design; the
slow reproduction tests check all of them against the summaries they write.
"""

from __future__ import annotations

import re
import string
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

PAGE = Path(__file__).resolve().parents[1] / "docs" / "paper-notes.md"

Value = str | tuple[str, ...] | Callable[[Mapping[str, Any]], Any]


@dataclass(frozen=True)
class Quote:
    """Text of the page with ``{name:spec}`` fields and, per field, where its value comes from."""

    text: str
    values: Mapping[str, Value]


def number(value: float, spec: str) -> str:
    """``format(value, spec)`` written as the page writes numbers."""
    text = re.sub(r"e([+-])0*(\d)", lambda m: "e" + m.group(1).replace("+", "") + m.group(2), format(value, spec))
    return "−" + text[1:] if text.startswith("-") else text


def spectrum(values: list[Any], spec: str) -> str:
    """Eigenvalues (``{"re", "im"}`` items of a summary) sorted by real part, a conjugate pair as ``a ± bi``."""
    items = sorted((v["re"], v["im"]) if isinstance(v, dict) else (float(v), 0.0) for v in values)
    return ", ".join(number(re_, spec) + (f" ± {number(abs(im), spec)}i" if im else "") for re_, im in items if im >= 0)


class _Formatter(string.Formatter):
    def __init__(self, summary: Mapping[str, Any], values: Mapping[str, Value]) -> None:
        self.summary, self.values = summary, values

    def get_value(self, key: int | str, args: Any, kwargs: Any) -> Any:
        source = self.values[str(key)]
        if callable(source):
            return source(self.summary)
        return lookup(self.summary, source)

    def format_field(self, value: Any, format_spec: str) -> str:
        if isinstance(value, str):
            return value
        spec, _, joiner = format_spec.partition("|")
        if isinstance(value, list):
            return (joiner or ", ").join(number(v, spec) for v in value)
        return number(value, spec)


def lookup(summary: Mapping[str, Any], path: str | tuple[str, ...]) -> Any:
    """The value at a dot-separated key path, or a tuple of keys (for keys with dots); indices as numbers."""
    value: Any = summary
    for part in path.split(".") if isinstance(path, str) else path:
        value = value[int(part)] if isinstance(value, list) else value[part]
    return value


def render(quote: Quote, summary: Mapping[str, Any]) -> str:
    """The quote's text with its fields filled from ``summary`` (KeyError when a key is missing)."""
    return _Formatter(summary, quote.values).format(quote.text)


def _collapsed(text: str) -> str:
    return " ".join(text.split())


def misquoted(name: str, summary: Mapping[str, Any], partial: bool = False) -> tuple[list[str], int]:
    """Quotes of reproduction ``name`` that the page does not show as ``summary`` has them.

    Parameters
    ----------
    name : str
        Reproduction name (a key of :data:`QUOTES`).
    summary : mapping
        Its summary, as read from ``summary.json``.
    partial : bool
        Skip quotes whose keys the summary lacks (a summary of the design part only).

    Returns
    -------
    tuple of (list of str, int)
        The problems and how many quotes were compared, as :func:`unquoted` returns them.
    """
    return unquoted(PAGE, QUOTES[name], summary, partial)


def unquoted(
    page: Path, quotes: list[Quote], values: Mapping[str, Any], partial: bool = False
) -> tuple[list[str], int]:
    """Quotes that ``page`` does not show as ``values`` has them (see :func:`misquoted`).

    Parameters
    ----------
    page : Path
        The markdown page.
    quotes : list of Quote
        Its quotes.
    values : mapping
        What their fields read (a summary, or benchmark results).
    partial : bool
        Skip quotes whose keys ``values`` lacks.

    Returns
    -------
    problems : list of str
        One line per quote the page does not show (or whose key is missing when not ``partial``).
    checked : int
        How many quotes were compared.
    """
    text_of_page = _collapsed(page.read_text())
    problems, checked = [], 0
    for quote in quotes:
        try:
            text = _collapsed(render(quote, values))
        except (KeyError, IndexError) as missing:
            if not partial:
                problems.append(f"{quote.text!r}: no key {missing}")
            continue
        checked += 1
        if text not in text_of_page:
            problems.append(f"docs/{page.name} should say {text!r}")
    return problems, checked


def _misprint(entry: str, field: str) -> Callable[[Mapping[str, Any]], float]:
    return lambda s: next(m[field] for m in s["paper"]["checks"]["misprints"] if m["entry"] == entry)


def _rounding_level(path: str) -> Callable[[Mapping[str, Any]], str]:
    """A residual that only rounding makes nonzero, quoted as the bound it stays under (its digits vary by LAPACK)."""

    def bound(s: Mapping[str, Any]) -> str:
        value = float(lookup(s, path))
        return "below 1e-6" if value < 1e-6 else f"{value:.0e}"

    return bound


def _rho_ratio(s: Mapping[str, Any]) -> str:
    d = s["design"]
    ratios = [p / o for key in ("x", "xi") for p, o in zip(d[f"paper_formula_rho_{key}"], d[f"rho_{key}"])]
    return f"{number(min(ratios), '.1f')}–{number(max(ratios), '.1f')}"


def _initial_over_rho(s: Mapping[str, Any]) -> str:
    d = s["design"]
    return f"{d['initial_width'] / max(d['rho_x']):.0f}–{d['initial_width'] / min(d['rho_x']):.0f}"


_E = "design.euler_radius_factor"
_PAPER_EULER = "design.paper_euler_scheme"


def _euler(theta: str, index: int) -> Callable[[Mapping[str, Any]], float]:
    return lambda s: lookup(s, _E)[f"theta={theta}"][index]


def _paper_euler(theta: str) -> Callable[[Mapping[str, Any]], Any]:
    return lambda s: lookup(s, _PAPER_EULER)[f"theta={theta}"]


QUOTES: dict[str, list[Quote]] = {
    "aircraft-uio": [
        Quote("(`PD` = {v:.0e})", {"v": "design.PD_residual"}),
        *(
            Quote(
                f"| {entry} | {{p:{printed}}} | {{c:{computed}}} |",
                {"p": _misprint(entry, "printed"), "c": _misprint(entry, "computed")},
            )
            for entry, printed, computed in (
                ("E(2,1)", "+.4f", ".5f"),
                ("E(2,2)", ".3e", ".3e"),
                ("P(2,3)", "+.3e", ".3e"),
                ("P(3,4)", "+.3e", ".3e"),
            )
        ),
        Quote("the other 41 agree to {v:.1e}", {"v": "paper.checks.max_difference_elsewhere"}),
        Quote(
            "(smallest singular value of the observability matrix {v:.3f})", {"v": "design.observability_margin_PA_C"}
        ),
        Quote("`eig(PA − KC)` = {{{v}}}", {"v": lambda s: spectrum(s["paper"]["checks"]["printed_K_eig_N"], ".2f")}),
        Quote("entries down to **{v:.2f}**", {"v": "paper.checks.printed_K_T_metzler_check"}),
        Quote("the smallest Σρ_x wins: {{{v:.3g}}}", {"v": "design.poles"}),
        Quote("`T N T⁻¹ − M` is {v}", {"v": _rounding_level("design.max_abs_TNTinv_minus_M")}),
        Quote("(T maps N onto M to {v},", {"v": _rounding_level("design.max_abs_TNTinv_minus_M")}),
        Quote("cond(T) = {v:.1f})", {"v": "design.cond_T"}),
        Quote(
            "but its Σρ_x is {c:.2f} against {r:.2f} for the real winner",
            {
                "c": "design.pole_candidates_score.complex pair x1",
                "r": lambda s: min(s["design"]["pole_candidates_score"].values()),
            },
        ),
        Quote(
            "ρ_x = {x:.3f| } vs {px:.3f| }; ρ_ξ = {xi:.3f| } vs {pxi:.3f| }",
            {
                "x": "design.rho_x",
                "px": "design.paper_formula_rho_x",
                "xi": "design.rho_xi",
                "pxi": "design.paper_formula_rho_xi",
            },
        ),
        Quote("terms), {v}× smaller than the paper's formula", {"v": _rho_ratio}),
        Quote("{v}× below the initial box width 2", {"v": _initial_over_rho}),
        Quote("λ₀²Te/4 = **{v:.2f}**", {"v": "design.hosm.paper_lambda100.max_error_after_transient"}),
        Quote("claimed µ₁δ̄^½ = {v:.2f}", {"v": "design.hosm.paper_lambda100.claimed_mu1_sqrt_delta"}),
        Quote("β = δ̇ + µ₁δ̄^½ = {v:.2f}", {"v": "design.hosm.paper_lambda100.beta_paper.0"}),
        Quote(
            "(fraction {f:.2f}, by up to {m:.3f},",
            {
                "f": "design.hosm.paper_lambda100.input_enclosure_with_beta_run0.fraction",
                "m": "design.hosm.paper_lambda100.input_enclosure_with_beta_run0.max_violation",
            },
        ),
        Quote(
            "(λ₀ = 1.5√L = {g:.1f}, L = {L:.1f})", {"g": "design.hosm.levant_gains.gains.0", "L": "design.derivative.L"}
        ),
        Quote(
            "gives {e:.3f} < β after {t:.3f} s",
            {
                "e": "design.hosm.levant_gains.max_error_after_transient",
                "t": "design.hosm.levant_gains.settling_time_to_beta",
            },
        ),
        Quote("= ±{v:.4f} for every admissible", {"v": "design.derivative.radius.0"}),
        Quote("The simulated |ψ̈| stays below {v:.1f}", {"v": "design.derivative.max_abs_psi_ddot_in_simulation"}),
        Quote("(max |ψ̈| in our runs: {v:.1f})", {"v": "design.derivative.max_abs_psi_ddot_in_simulation"}),
        Quote("; PB = {v:.0e}, the commands act", {"v": "design.known_inputs.PB_max"}),
        Quote(
            "mean widths after 1 s are {s:.7f}× (state) and ≤ {i:.5f}× (input)",
            {"s": "design.known_inputs.max_state_width_ratio", "i": "design.known_inputs.max_input_width_ratio"},
        ),
    ],
    "hgio-sampled": [
        Quote(
            "then eig = {v} (= printed p₁, ω₁)", {"v": lambda s: spectrum(s["design"]["printed_L1_eigenvalues"], ".5f")}
        ),
        Quote("(margins {a:.2f}, {b:.3f})", {"a": "design.disk_margins.0", "b": "design.disk_margins.1"}),
        Quote("| −1 (implied by θ − α) | {v:.3f} |", {"v": "design.lambda_min_M2"}),
        Quote(
            "| {pa:.4f} (paper reading, printed L₁, v₁) · {oa:.3f} (paper reading, our L₁ = 0, canonical v₁) · "
            "{sp:.4f} / {so:.4f} (sound reading, printed / our L₁) |",
            {
                "pa": "design.theorem44_with_printed_L1_v1.alpha_paper_reading",
                "oa": "design.theorem44_ours.alpha_paper_reading",
                "sp": "design.theorem44_with_printed_L1_v1.alpha_sound_reading",
                "so": "design.theorem44_ours.alpha_sound_reading",
            },
        ),
        Quote(
            "| {pt:.4f} / {ot:.3f} / {sp:.4f} / {so:.4f} |",
            {
                "pt": "design.theorem44_with_printed_L1_v1.theta_paper_reading",
                "ot": "design.theorem44_ours.theta_paper_reading",
                "sp": "design.theorem44_with_printed_L1_v1.theta_sound_reading",
                "so": "design.theorem44_ours.theta_sound_reading",
            },
        ),
        Quote("\\|v₁dʳ\\| = ({v:.3f})", {"v": "design.theorem44_ours.abs_v1_dr_at_t0"}),
        Quote(
            "(34) holds only from t = {v:.3f} s", {"v": "design.theorem44_with_printed_L1_v1.condition34_from_t_paper"}
        ),
        Quote("log({v:.4f}/0.08)", {"v": "design.theorem44_with_printed_L1_v1.abs_v1_dr_at_t0.0"}),
        Quote(
            "abscissa {p:+.3f} (printed α, θ); {s:+.3f} (sound α, θ)",
            {
                "p": "design.theorem44_with_printed_L1_v1.mat35_abscissa_paper",
                "s": "design.theorem44_with_printed_L1_v1.mat35_abscissa_sound",
            },
        ),
        Quote(
            "x₁ {a:.1f}, x₂ {b:.4f}, x₃ {c:.4f} with K = (1,0,0); {d:.2g}, {e:.0e}, {f:.1e} with K = (3,3,1)",
            {
                "a": "design.width_ratio_constructive_over_theta1000.0",
                "b": "design.width_ratio_constructive_over_theta1000.1",
                "c": "design.width_ratio_constructive_over_theta1000.2",
                "d": "design.binomial_design.width_ratio_constructive_over_binomial.0",
                "e": "design.binomial_design.width_ratio_constructive_over_binomial.1",
                "f": "design.binomial_design.width_ratio_constructive_over_binomial.2",
            },
        ),
        Quote(
            "(`euler_radius_factor`, p = −0.5): {a:.3f} at θ = 9.76, {b:.2g} at θ = 1000",
            {"a": _euler("9.7585", 1), "b": _euler("1000", 1)},
        ),
        Quote(
            "θ = 9.76 gives bounds {v:.1f} % narrower",
            {"v": lambda s: 100 * (1 - _mean(_paper_euler("9.7585")(s)["width_over_exact"]))},
        ),
        Quote(
            "θ = 100 gives {a:.0f}–{b:.0f}× narrower bounds that enclose {f:.0f} % of the samples "
            "(violation {m:.1f}, first at {t:.0f} ms); θ = 1000 encloses {g:.1f} %",
            {
                "a": lambda s: 1 / max(_paper_euler("100")(s)["width_over_exact"]),
                "b": lambda s: 1 / min(_paper_euler("100")(s)["width_over_exact"]),
                "f": lambda s: 100 * _paper_euler("100")(s)["enclosure"]["fraction"],
                "m": lambda s: _paper_euler("100")(s)["enclosure"]["max_violation"],
                "t": lambda s: 1000 * _paper_euler("100")(s)["first_violation_s"],
                "g": lambda s: 100 * _paper_euler("1000")(s)["enclosure"]["fraction"],
            },
        ),
        Quote("(mean widths {v:.1f}).", {"v": "design.constructive_width_mean_theorem45"}),
        Quote(
            "gets x₁ to {a:.2f} ({b:.2f} with the output measured at every step",
            {
                "a": "design.arbitrary_design.width_mean_theorem45.0",
                "b": "design.arbitrary_design.continuous_output.width_mean_theorem45.0",
            },
        ),
        Quote(
            "eigenvalues {re:.0f} ± {im:.0f}i",
            {"re": "design.binomial_design.eigenvalues.0.re", "im": "design.binomial_design.eigenvalues.0.im"},
        ),
        Quote(
            "(all three contain x(t_k)): mean widths {a:.2f}, {b:.1f}, {c:.1f}.",
            {
                "a": "design.constructive_width_mean_refined.0",
                "b": "design.constructive_width_mean_refined.1",
                "c": "design.constructive_width_mean_refined.2",
            },
        ),
        Quote(
            "give L₁ = ({l:.2f}) and refined widths {a:.2f}, {b:.1f}, {c:.1f} — "
            "x₂, x₃ {r2:.1f}× and {r3:.1f}× narrower",
            {
                "l": "design.tuned_disks_design.L1",
                "a": "design.tuned_disks_design.width_mean_refined.0",
                "b": "design.tuned_disks_design.width_mean_refined.1",
                "c": "design.tuned_disks_design.width_mean_refined.2",
                "r2": lambda s: _tuned_ratio(s, 1),
                "r3": lambda s: _tuned_ratio(s, 2),
            },
        ),
        Quote("mean output width {v:.2f} for |V| ≤ 0.1", {"v": "design.output_width_mean"}),
        Quote(
            "L₁ = ({l:.3f}), eigenvalues {e}, cond(v₁) {c:.1f}; bound of the Theorem 4.5 box {b2:.2f} / {b3:.2f} for "
            "x₂/x₃, measured {m2:.2f} / {m3:.2f}",
            {
                "l": "design.width_design.L1",
                "e": lambda s: spectrum(s["design"]["width_design"]["eigenvalues"], ".2f"),
                "c": "design.width_design.v1_condition",
                "b2": "design.width_design.bound_width_mean_theorem45.1",
                "b3": "design.width_design.bound_width_mean_theorem45.2",
                "m2": "design.width_design.measured_width_mean_theorem45.1",
                "m3": "design.width_design.measured_width_mean_theorem45.2",
            },
        ),
        Quote(
            "mean output width {a:.2f} → {b:.2f})",
            {"a": "design.output_width_mean", "b": "design.width_design.output_width_mean"},
        ),
        Quote(
            "Mean widths x₁/x₂/x₃: **{a:.2f} / {b:.2f} / {c:.2f}** "
            "(paper-faithful constructive {d:.2f} / {e:.1f} / {f:.1f};",
            {
                "a": "design.width_design.width_mean.0",
                "b": "design.width_design.width_mean.1",
                "c": "design.width_design.width_mean.2",
                "d": "design.previous_recommended_width_mean.0",
                "e": "design.previous_recommended_width_mean.1",
                "f": "design.previous_recommended_width_mean.2",
            },
        ),
        Quote(
            "{h:.3g| / }): {a:.1f}× / {b:.2f}× / {c:.2f}×",
            {
                "h": "design.reference.width_mean",
                "a": "design.width_design.width_over_hull.0",
                "b": "design.width_design.width_over_hull.1",
                "c": "design.width_design.width_over_hull.2",
            },
        ),
        Quote(
            "step 8 (radius matrix with own-box injection) is {v:+.2f} for the width gain",
            {"v": "design.width_design.radius_matrix_abscissa"},
        ),
        Quote("whose gain stays 0 (abscissa {v:.1f})", {"v": "design.width_design.output_radius_abscissa"}),
    ],
    "numerical-3state": [
        Quote(
            "ours [{g:.5g}] vs printed [0.3 0.2 0.8], γ = {c:.4f}",
            {"g": "design.system_68.gains.(54)-(55).gain", "c": "design.system_68.gains.(54)-(55).gamma"},
        ),
        Quote(
            "feasible and gives L = [{g:.3f}] with A0 − LC still holding {m:.1f}",
            {
                "g": "design.system_70.gains.(54) with full P (printed form).gain",
                "m": "design.system_70.gains.(54) with full P (printed form).min_entry",
            },
        ),
        Quote("(an LP; shift ≤ {v:.0e})", {"v": "design.system_68.gains.(54)-(55).projection_shift"}),
        Quote(
            "Ours (68): [{g:.4f}] vs printed (Thm 3.4 + 3.5) [{p:.4f| }]",
            {
                "g": "design.system_68.gains.(26).gain",
                "p": ("paper", "system_68", "set_based_thm3.4+3.5", "gain"),
            },
        ),
        Quote(
            "(70) set-based (19) [{g:.4f| }]: ρ(M) = {r:.3f}",
            {"g": "paper.system_70.set_based_(19).gain", "r": "paper.system_70.set_based_(19).spectral_radius"},
        ),
        Quote(
            "(70) interval (54a) [{g:.4f| }]: min entry {m:.3f}; the literal (39) loses the truth by up to {v:.2f}",
            {
                "g": "paper.system_70.interval_(54a)-(55a).gain",
                "m": "paper.system_70.interval_(54a)-(55a).min_entry",
                "v": "design.system_70.naive.naive_interval_printed_(54a).max_violation",
            },
        ),
        Quote(
            '(70) "integrated" [{g:.4f| }]: not monotone ({m:.1f}), stable',
            {"g": "paper.system_70.integrated_(19)+(65).gain", "m": "paper.system_70.integrated_(19)+(65).min_entry"},
        ),
        Quote(
            "(68) monotone gain {a:.4f}, (70) (19) gain {b:.4f},",
            {
                "a": "design.system_68.gains.(54)-(55).width_spectral_radius",
                "b": "design.system_70.gains.(19).width_spectral_radius",
            },
        ),
        Quote(
            "mean-width ratio interval/zonotopic {v:.3f} on (68),",
            {"v": "design.system_68.width_ratio_interval_over_zonotopic.mean"},
        ),
        Quote(
            "on (70) zonotopic/interval = {v:.3f}", {"v": "design.system_70.width_ratio_zonotopic_over_interval.mean"}
        ),
        Quote(
            "on the monotone cases they coincide (ratio {v:.3f})",
            {"v": "design.system_68.width_ratio_zonotopic_same_gain_over_interval.mean"},
        ),
        Quote(
            "listed as `tube`: {a:.3f} × the framer on (68) and the tank, {b:.3f} × on (70)",
            {
                "a": "design.system_68.width_ratio_tube_over_interval.mean",
                "b": "design.system_70.width_ratio_tube_over_interval.mean",
            },
        ),
        Quote(
            "diverges (width {v:.0e} at k = 199)",
            {"v": "design.system_70.naive.naive_zonotopic_printed_(19).final_width_max"},
        ),
        Quote("reduction order q = 5n = {v}", {"v": lambda s: str(s["design"]["choices"]["reduction_order"])}),
    ],
    "two-tank": [
        Quote(
            "tank: [{g:.4f}] vs printed [{p:.4f| }]",
            {"g": "design.gains.(26).gain", "p": ("paper", "gains", "set_based_thm3.4+3.5", "gain")},
        ),
        Quote(
            "Tank (19) [{g:.4f| }]: ρ(|M|) = {a:.7f}, ρ(|M| + D) = {w:.3f}",
            {
                "g": "paper.gains.set_based_(19).gain",
                "a": "paper.gains.set_based_(19).abs_spectral_radius",
                "w": "paper.gains.set_based_(19).width_spectral_radius",
            },
        ),
        Quote(
            "Tank (54a) [{g:.4f| }]: literal (39) loses the truth by up to {v:.1f} cm",
            {
                "g": "paper.gains.interval_(54a)-(55a).gain",
                "v": "design.naive.naive_interval_printed_(54a).max_violation",
            },
        ),
        Quote(
            'Tank "monotone" (54)-(55) and integrated [{g:.4g| }]: min entry {m:.3f} (not monotone); '
            "set-based [{s:.4f| }]: {n:.2f}",
            {
                "g": "paper.gains.interval_(54)-(55).gain",
                "m": "paper.gains.interval_(54)-(55).min_entry",
                "s": ("paper", "gains", "set_based_thm3.4+3.5", "gain"),
                "n": ("paper", "gains", "set_based_thm3.4+3.5", "min_entry"),
            },
        ),
        Quote("Ours (diag P): [{g:.5g}], M ≥ 0", {"g": "design.gains.(54)-(55).gain"}),
        Quote(
            "Our (19) tank gain [{g:.3f}] (printed [0.6647 0.6542]; same defect: ρ(|M|) = {a:.4f})",
            {"g": "design.gains.(19).gain", "a": "design.gains.(19).abs_spectral_radius"},
        ),
        Quote("tank monotone gain {v:.4f}.", {"v": "design.gains.(54)-(55).width_spectral_radius"}),
        Quote(
            "the tank (19) gain is uncertified, {v:.3f},",
            {"v": "design.observers.zonotopic_hinf.certificate_spectral_radius"},
        ),
        Quote(
            "{v:.3f} on the tank (zonotopic gain from (26))", {"v": "design.width_ratio_interval_over_zonotopic.mean"}
        ),
        Quote("{v:.3f} × the framer on (68) and the tank", {"v": "design.width_ratio_tube_over_interval.mean"}),
    ],
    "manipulator-lpv": [
        Quote("(largest |CB_un| entry over the test points: {v:.1f})", {"v": "angles_only.C_B_un_max_abs"}),
        Quote("λ = {v:.0f} (the paper's) is kept", {"v": "angles_only.lambda"}),
        Quote(
            "faults included (fraction {f:.1f}, violation {v:.1f})",
            {"f": lambda s: _angles_only_min(s, "fraction"), "v": lambda s: -_angles_only_min(s, "max_violation")},
        ),
        Quote(
            "Its mean velocity widths after {a:.1f} s in scenario 1 are {v:.4f| and } rad/s",
            {"a": "angles_only.width_after_s", "v": "angles_only.scenarios.1.velocity_width_mean"},
        ),
        Quote(
            "(max {v:.4f| and }; |q̇| reaches {a:.2f| and })",
            {"v": "angles_only.scenarios.1.velocity_width_max", "a": "angles_only.scenarios.1.velocity_abs_max"},
        ),
        Quote(
            "Isolation: fault 1 at {b:.3f} s in scenario 2, fault 2 at {c:.3f} s in scenario 3, both at "
            "{d:.3f| and } s in scenario 4",
            {
                "b": "angles_only.scenarios.2.detection_time_s.0",
                "c": "angles_only.scenarios.3.detection_time_s.0",
                "d": "angles_only.scenarios.4.detection_time_s",
            },
        ),
        Quote(
            "smallest signal of the two hypotheses before 20 s is {v:.1e| and }",
            {"v": "angles_only.scenarios.1.min_signal_before_onset"},
        ),
    ],
}
"""Every number of the seed 000, 002 and 004 sections that a reproduction's summary holds (seed 001: the
angles-only section)."""


def _angles_only_min(s: Mapping[str, Any], key: str) -> float:
    """Smallest fraction (or largest violation, as its negative) of the angles-only state box over the scenarios."""
    values = [sc["state_enclosure"][key] for sc in s["angles_only"]["scenarios"].values()]
    return min(values) if key == "fraction" else -max(values)


def _mean(values: list[float]) -> float:
    return sum(values) / len(values)


def _tuned_ratio(s: Mapping[str, Any], i: int) -> float:
    tuned = s["design"]["tuned_disks_design"]
    return float(tuned["constructive_width_mean_refined_same_window"][i] / tuned["width_mean_refined"][i])
