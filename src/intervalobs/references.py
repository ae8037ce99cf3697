"""The five papers the package implements, each with the one short name the code and the pages use.

Docstrings, reproduction summaries and ``intervalobs list`` name a paper by its short name below; the
paper's theorem, hypothesis and equation numbers appear in a docstring's ``References`` section (or a
Notes section that cites the paper), never in an error message (an error says what the condition means
for the user's system). Where the code departs from a printed design, ``docs/paper-notes.md`` says why,
with numbers.

Each citation gives what could be checked against a second source (a bibliographic record, a listing
of the paper, or a reference list of another paper that cites it) and says which fields could not be
(:attr:`Paper.unverified`): our copies are plain-text extractions without title pages, so a field read
only from the text's style or content is marked unverified rather than guessed.

**References.**

- *the aircraft UIO paper*: D. Gucik-Derigny, T. Raïssi, A. Zolghadri, "Interval state and unknown
  inputs estimation for linear time-invariant systems", IFAC Proceedings Volumes 47 (19th IFAC World
  Congress), 2014, pp. 7375–7381, HAL hal-00984625. Authors, title, venue, volume, year, pages and HAL
  identifier checked against the reference lists of two later HAL papers that cite it (our copy lacks
  the title page; its abstract, example and reference style match); the DOI was not found. An
  unknown-input interval observer for uncertain LTI continuous-time systems, on a fifth-order lateral
  model of a fixed-wing aircraft.
- *Rotondo et al.*: D. Rotondo, A. Cristofaro, T. A. Johansen, F. Nejjari, V. Puig, "State estimation
  and decoupling of unknown inputs in uncertain LPV systems using interval observers". Title and authors
  from the title page of our copy (affiliations NTNU Trondheim, UPC Terrassa, Camerino, IRI Barcelona);
  a Taylor & Francis journal's layout, references up to 2015, funding up to 2015. Venue, year and DOI
  not verified: no second source for them was found. An LPV interval observer
  and interval unknown-input observer with fault isolation, on a two-joint planar manipulator.
- *the integrated-observer paper*: a journal article comparing zonotopic set-based, interval and
  integrated interval observers for discrete-time linear systems with time-invariant and time-varying
  uncertainties, with H∞ gains from LMIs, on a three-state numerical example and a two-tank system.
  Our copy starts at the abstract: the descriptive title used here is taken from it. Authors, title,
  venue, year and DOI not verified; what the text shows: a Taylor & Francis author–year style, its
  references run to 2018 (so it appeared in 2018 or later), and it builds on the zonotope and
  interval-observer work of Puig, Combastel and Pourasghar et al. (2017), whom it cites most.
- *Khajenejad & Yong*: M. Khajenejad, S. Z. Yong, "Simultaneous input and state interval observers
  for nonlinear systems with rank-deficient direct feedthrough", arXiv:2004.01861 [eess.SY], 2020
  (v2 of December 2020; DOI of the preprint 10.48550/arXiv.2004.01861). Title, authors and arXiv
  number checked against the arXiv listing; a later journal or conference version was not verified.
  Interval bounds of the state and of unknown inputs for nonlinear discrete-time systems.
- *the sampled-output high-gain paper*: a journal article proposing a high-gain interval observer
  (HGIO) for partially linear continuous-time systems with sampled measured outputs, its gain placed
  by pole placement in disk LMI regions and a time-varying change of coordinates. Our copy starts at
  the abstract. Authors, title, venue, year and DOI not verified; what the text shows: a Taylor &
  Francis author–year style, references up to 2021, and its θ = 1000 comparison is "a previous work",
  the earlier design of Thabet et al. (2021), on the same numerical example (so it appeared in 2021
  or later, from the group of that earlier design).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["PAPERS", "Paper", "short_name"]


@dataclass(frozen=True)
class Paper:
    """One source paper: the short name the code uses, its citation and what of it is unverified.

    Parameters
    ----------
    short : str
        The name used in docstrings, summaries and listings (e.g. ``"Rotondo et al."``).
    citation : str
        Authors, title, venue and year as far as verified (the module docstring says how).
    unverified : tuple of str
        The citation fields (``"authors"``, ``"title"``, ``"venue"``, ``"year"``, ``"DOI"``) that no
        second source confirmed; empty when every field is verified.
    """

    short: str
    citation: str
    unverified: tuple[str, ...] = ()


PAPERS: dict[str, Paper] = {
    "000_8977db2ea356505f.txt": Paper(
        "the aircraft UIO paper",
        "Gucik-Derigny, Raïssi, Zolghadri, Interval state and unknown inputs estimation for linear "
        "time-invariant systems, IFAC Proceedings Volumes 47, pp. 7375-7381, 2014, HAL hal-00984625",
        ("DOI",),
    ),
    "001_a32a6ad4c1850a1f.txt": Paper(
        "Rotondo et al.",
        "Rotondo, Cristofaro, Johansen, Nejjari, Puig, State estimation and decoupling of unknown inputs "
        "in uncertain LPV systems using interval observers (Taylor & Francis journal article, after 2015)",
        ("venue", "year", "DOI"),
    ),
    "002_a6311576c67046f0.txt": Paper(
        "the integrated-observer paper",
        "Zonotopic, interval and integrated interval observers for linear systems with time-invariant "
        "and time-varying uncertainties (descriptive title; Taylor & Francis journal article, 2018 or later)",
        ("authors", "title", "venue", "year", "DOI"),
    ),
    "003_ab28b8d9baa98fb8.txt": Paper(
        "Khajenejad & Yong",
        "Khajenejad, Yong, Simultaneous input and state interval observers for nonlinear systems with "
        "rank-deficient direct feedthrough, arXiv:2004.01861, 2020, doi:10.48550/arXiv.2004.01861",
    ),
    "004_a01fe651baa78161.txt": Paper(
        "the sampled-output high-gain paper",
        "A high-gain interval observer for partially linear continuous-time systems with sampled measured "
        "outputs (descriptive title; Taylor & Francis journal article, 2021 or later)",
        ("authors", "title", "venue", "year", "DOI"),
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
