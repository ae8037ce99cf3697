"""The five papers the package implements, each with the one short name the code and the pages use.

Docstrings, reproduction summaries and ``intervalobs list`` name a paper by its short name below; the
paper's theorem, hypothesis and equation numbers appear next to a formula in a docstring, never in an
error message (an error says what the condition means for the user's system). Where the code departs
from a printed design, ``docs/paper-notes.md`` says why, with numbers.

**References.**

- *the aircraft UIO paper*: D. Gucik-Derigny, T. Raïssi, A. Zolghadri, "Interval state and unknown
  inputs estimation for linear time-invariant systems", IFAC Proceedings Volumes 47(3) (19th IFAC
  World Congress), 2014, pp. 7375–7381, HAL hal-00984625. An unknown-input interval observer for
  uncertain LTI continuous-time systems, on a fifth-order lateral model of a fixed-wing aircraft.
  (Identified from the extracted text's abstract, reference style and example; the extraction lacks
  the title page.)
- *Rotondo et al.*: D. Rotondo, A. Cristofaro, T. A. Johansen, F. Nejjari, V. Puig, "State estimation
  and decoupling of unknown inputs in uncertain LPV systems using interval observers", a Taylor &
  Francis journal article (its references run to 2015; venue, year and DOI not verified). An LPV
  interval observer and interval unknown-input observer with fault
  isolation, on a two-joint planar manipulator.
- *the integrated-observer paper*: "interval observers for linear systems with time-invariant and
  time-varying uncertainties" (journal article; the extraction lacks the title page, authors and venue
  unverified). Zonotopic set-based, interval and integrated interval observers with H∞ gains from LMIs,
  on a three-state numerical example and a two-tank system.
- *Khajenejad & Yong*: M. Khajenejad, S. Z. Yong, "Simultaneous input and state interval observers
  for nonlinear systems with rank-deficient direct feedthrough", arXiv:2004.01861, 2020. Interval
  bounds of the state and of unknown inputs for nonlinear discrete-time systems.
- *the sampled-output high-gain paper*: "a high-gain interval observer for partially linear
  continuous-time systems with sampled measured outputs" (journal article; the extraction lacks the
  title page, authors and venue unverified). Its gain placed by pole placement in disk LMI regions; its
  θ = 1000 comparison is the earlier design of Thabet et al. (2021).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["PAPERS", "Paper", "short_name"]


@dataclass(frozen=True)
class Paper:
    """One source paper: the short name the code uses and its citation.

    Parameters
    ----------
    short : str
        The name used in docstrings, summaries and listings (e.g. ``"Rotondo et al."``).
    citation : str
        Authors, title, venue and year as far as verified (the module docstring says what is not).
    """

    short: str
    citation: str


PAPERS: dict[str, Paper] = {
    "000_8977db2ea356505f.txt": Paper(
        "the aircraft UIO paper",
        "Gucik-Derigny, Raïssi, Zolghadri, Interval state and unknown inputs estimation for linear "
        "time-invariant systems, IFAC Proceedings Volumes 47(3), 2014",
    ),
    "001_a32a6ad4c1850a1f.txt": Paper(
        "Rotondo et al.",
        "Rotondo, Cristofaro, Johansen, Nejjari, Puig, State estimation and decoupling of unknown inputs "
        "in uncertain LPV systems using interval observers (journal article, after 2015)",
    ),
    "002_a6311576c67046f0.txt": Paper(
        "the integrated-observer paper",
        "Interval observers for linear systems with time-invariant and time-varying uncertainties "
        "(zonotopic, interval and integrated observers)",
    ),
    "003_ab28b8d9baa98fb8.txt": Paper(
        "Khajenejad & Yong",
        "Khajenejad, Yong, Simultaneous input and state interval observers for nonlinear systems with "
        "rank-deficient direct feedthrough, arXiv:2004.01861, 2020",
    ),
    "004_a01fe651baa78161.txt": Paper(
        "the sampled-output high-gain paper",
        "A high-gain interval observer for partially linear continuous-time systems with sampled outputs",
    ),
}
"""Each source paper by the name of its text file in the project's notes (the ``seed`` of a summary)."""


def short_name(source: str) -> str:
    """The short name of a paper from its text file's name, or ``"ours"`` for an example of our own.

    Parameters
    ----------
    source : str
        A key of :data:`PAPERS`, or ``"-"`` for an example that comes from no paper.

    Returns
    -------
    str
        The paper's short name.
    """
    paper = PAPERS.get(source)
    return paper.short if paper is not None else "ours"
