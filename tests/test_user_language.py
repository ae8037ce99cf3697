"""The user's language: no paper-internal references in error messages, warnings or the user pages.

Error messages and warnings (the strings of every ``raise`` and ``warnings.warn`` in the package) and the user pages
(README.md, docs/*.md except docs/paper-notes.md, which maps the papers to the code, and the markdown cells of the
notebooks) say what a condition means for the user's system; the paper and its theorem, hypothesis and equation
numbers belong in a docstring's ``References`` section or in the References block of :mod:`intervalobs.references`.
The bodies of public docstrings (every public class, function, method and property, :mod:`public_api`) are scanned
too: outside a ``References`` section, a ``Notes`` section that cites one of the five papers by its short name, and
a paragraph opened by ``**Reference.**``, they name no numbered theorem, lemma, hypothesis, assumption, proposition,
corollary or algorithm, no equation number and no paper symbol. The papers' file numbers ("seed 00N") appear nowhere
in the package, not even in a docstring: only docs/paper-notes.md names them.

Allow-list (the only exceptions):

- ``seed`` as a random-number seed: the argument (``seed=``, ``seed:``, ``--seed``, in a code span),
  seeds numbered 0, 1, 2 … (never 00N), and "per seed", "the seeds", "three seeds" and the like;
- ``MESSAGE_ALLOWED``: the option values of ``ZonotopicObserver.design(lmi=...)``, which are the
  paper's equation labels by design (in a docstring, a quoted ``"(26)"`` is not an equation reference);
- ``DOCSTRING_ALLOWED_PREFIXES``: the docstrings of :mod:`intervalobs.reproduce`, which map each
  paper's printed design and numbers to the code. Module docstrings are not scanned: they are the
  developer's map of a module to its paper.
"""

from __future__ import annotations

import ast
import inspect
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "intervalobs"
PAPER_TERMS = re.compile(
    r"(?i:\bseeds?\b)|\bTheorems?\b|\bHypothes[ie]s\b|\bH-matrix\b|U2'g|\bLemmas?\b|\bCorollar(?:y|ies)\b"
    r"|\bPropositions?\b|\bAssumptions? \d|\bAlgorithm \d|\beqs?\. ?\("
)
"""Paper-internal names: "seed" (the papers' file numbers), theorem, hypothesis, lemma, corollary,
proposition, numbered assumption and algorithm references, equation references and the papers' symbols.
Capitalised words only, except "seed": "a hypothesis bank" or "Smolyak's theorem" is plain English."""
RANDOM_SEED = re.compile(
    r"--seed\b|\bseed\s*[=:]|\bseeds?\s+(?!00)\d|\"seeds?\""
    r"|\b(?:per|each|worst|random|held-out|over the|the|of the|three|two|\d+) seeds\b"
    r"|\b(?:per|each|worst|random) seed\b",
    re.IGNORECASE,
)
"""A "seed" that is a random-number seed, not a paper (see the module's allow-list)."""
CODE_SPAN = re.compile(r"`[^`\n]+`")
"""An inline code span of a page: it names an argument (``Example.run(out, seed, ...)``), never a paper."""
PAPER_FILE = re.compile(r"\b[Ss]eeds? 00\d")
"""A paper's file number, allowed only in docs/paper-notes.md."""
MESSAGE_ALLOWED = {("observers/zonotopic.py", "lmi: expected '(26)' or '(19)', got ")}
"""(module, message) pairs allowed to keep an equation label: the values of an option."""
PAGES = [
    ROOT / "README.md",
    *(p for p in sorted((ROOT / "docs").glob("*.md")) if p.name != "paper-notes.md"),
]
NOTEBOOKS = sorted((ROOT / "docs" / "notebooks").glob("*.ipynb"))
MODULES = sorted(PACKAGE.rglob("*.py"))


def paper_terms(text: str, code_spans: bool = False) -> list[str]:
    """The paper-internal names in a text, random-number seeds (and, on a page, code spans) excepted.

    Parameters
    ----------
    text : str
        An error message, a warning or a page.
    code_spans : bool
        Whether the text is markdown whose inline code spans may name a ``seed`` argument.

    Returns
    -------
    list of str
        Each offending word, in order.
    """
    allowed = [m.span() for m in RANDOM_SEED.finditer(text)]
    if code_spans:
        allowed += [m.span() for m in CODE_SPAN.finditer(text)]
    found = []
    for match in PAPER_TERMS.finditer(text):
        is_seed = match.group(0).lower().startswith("seed")
        if is_seed and any(start <= match.start() < end for start, end in allowed):
            continue
        found.append(match.group(0))
    return found


def _is_warning(node: ast.AST) -> bool:
    """Whether a node is a call of ``warnings.warn`` (or a bare ``warn``)."""
    if not isinstance(node, ast.Call):
        return False
    func = node.func
    return (isinstance(func, ast.Attribute) and func.attr == "warn") or (
        isinstance(func, ast.Name) and func.id == "warn"
    )


def messages(source: str) -> list[tuple[int, str]]:
    """(line, text) of the string parts of every ``raise`` and ``warnings.warn`` of a module's source."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Raise) and node.exc is not None:
            target: ast.AST = node.exc
        elif _is_warning(node):
            target = node
        else:
            continue
        parts = [n.value for n in ast.walk(target) if isinstance(n, ast.Constant) and isinstance(n.value, str)]
        found.append((node.lineno, " ".join(parts)))
    return found


def _markdown_of(notebook: Path) -> str:
    """The markdown cells of a notebook, one text."""
    cells = json.loads(notebook.read_text(encoding="utf-8"))["cells"]
    return "\n\n".join("".join(cell["source"]) for cell in cells if cell["cell_type"] == "markdown")


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_error_messages_speak_of_the_system_not_the_paper(path: Path) -> None:
    module = path.relative_to(PACKAGE).as_posix()
    for line, text in messages(path.read_text(encoding="utf-8")):
        if (module, text) in MESSAGE_ALLOWED:
            continue
        terms = paper_terms(text)
        assert not terms, f"{path.relative_to(ROOT)}:{line}: message names {terms}: say what it means instead"


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_the_package_never_names_a_paper_by_its_file_number(path: Path) -> None:
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        assert not PAPER_FILE.search(line), f"{path.relative_to(ROOT)}:{number}: use the paper's short name"


@pytest.mark.parametrize("path", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_user_pages_speak_of_the_system_not_the_paper(path: Path) -> None:
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        terms = paper_terms(line, code_spans=True)
        assert not terms, f"{path.relative_to(ROOT)}:{number} names {terms}: {line.strip()[:80]}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_text_speaks_of_the_system_not_the_paper(path: Path) -> None:
    terms = paper_terms(_markdown_of(path), code_spans=True)
    assert not terms, f"{path.relative_to(ROOT)}: markdown names {terms}"


def test_the_pages_and_notebooks_are_found() -> None:
    names = {p.name for p in PAGES}
    assert {"README.md", "index.md", "guide.md", "design.md"} <= names and "paper-notes.md" not in names
    assert len(NOTEBOOKS) >= 3


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ('raise AssumptionError("Hypothesis 6 (seed 000)")', ["Hypothesis", "seed"]),
        ("Seed 003's Theorem 1 gains", ["Seed", "Theorem"]),
        ("the seed's Lemma 2 constant", ["seed", "Lemma"]),
        ("the H-matrix of Corollary 3.1, U2'g", ["H-matrix", "Corollary", "U2'g"]),
        (
            "under Assumption 2.2, Algorithm 1, eq. (13) and Proposition 3",
            ["Assumption 2", "Algorithm 1", "eq. (", "Proposition"],
        ),
        ("seeds 000 and 004", ["seeds"]),
        ("seed: expected a nonnegative integer; simulate(..., seed=3); --seed N", []),
        ("ranges over seeds 0, 1, 2; per seed; the worst seed; over the seeds; 5 seeds", []),
        ("a hypothesis bank; Smolyak's theorem", []),
    ],
    ids=[
        "hypothesis",
        "capital-seed",
        "the-seed",
        "symbols",
        "numbered",
        "two-papers",
        "rng-args",
        "rng-runs",
        "prose",
    ],
)
def test_the_scan_finds_a_paper_reference(text: str, expected: list[str]) -> None:
    assert paper_terms(text) == expected


def test_the_scan_reads_messages_warnings_and_code_spans() -> None:
    source = (
        "import warnings\n"
        "raise DesignError(f'LMI of Theorem {k}: infeasible')\n"
        "warnings.warn('the seed 002 gain', stacklevel=2)\n"
        "raise DataError('seed: expected an integer')\n"
    )
    found = [(line, paper_terms(text)) for line, text in messages(source)]
    assert sorted(found) == [(2, ["Theorem"]), (3, ["seed"]), (4, [])]
    assert paper_terms("`Example.run(out, seed, plots)`", code_spans=True) == []
    assert paper_terms("Example.run(out, seed, plots)") == ["seed"]
    assert PAPER_FILE.search("see seed 004") and not PAPER_FILE.search("seed 0 of the benchmark")


BUILTIN_ERRORS = {"TypeError", "ValueError", "RuntimeError", "KeyError", "IndexError", "OSError", "Exception"}
"""Builtins the package never raises itself: it raises the named error of :mod:`intervalobs.errors`
that subclasses the builtin (``AttributeError`` stays in a module's ``__getattr__``, ``NotImplementedError``
in an abstract method)."""


def _raised_builtins(source: str) -> list[tuple[int, str]]:
    """(line, name) of every ``raise`` of a builtin error in a module's source."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Raise) and node.exc is not None:
            call = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
            if isinstance(call, ast.Name) and call.id in BUILTIN_ERRORS:
                found.append((node.lineno, call.id))
    return found


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_errors_are_the_library_s_named_errors(path: Path) -> None:
    raised = _raised_builtins(path.read_text(encoding="utf-8"))
    assert not raised, f"{path.relative_to(ROOT)}: raises {raised}: use the named error of intervalobs.errors"


def test_the_scan_finds_a_builtin_error() -> None:
    assert _raised_builtins("raise ValueError('x')\nraise DataError('y')\nraise TypeError") == [
        (1, "ValueError"),
        (3, "TypeError"),
    ]


def _fenced_blocks(markdown: str) -> list[str]:
    """The fenced code blocks of a markdown text, in order (MyST directives included)."""
    return re.findall(r"^```[^\n]*\n(.*?)^```", markdown, flags=re.MULTILINE | re.DOTALL)


def test_the_readme_cites_all_five_papers_by_their_short_names() -> None:
    from intervalobs.references import PAPERS

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    references = readme[readme.index("## References") :]
    assert len(PAPERS) == 5
    for paper in PAPERS.values():
        assert f"**{paper.short}**" in references, f"README's References lacks {paper.short!r}"
    for author in ("Gucik-Derigny", "Rotondo", "Khajenejad", "arXiv:2004.01861"):
        assert author in references


def test_the_docs_index_opens_with_pip_install_and_observe() -> None:
    index = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    assert index.startswith("```{include} ../README.md"), "the index starts by including the README"
    readme_blocks = _fenced_blocks((ROOT / "README.md").read_text(encoding="utf-8"))
    assert readme_blocks[0].strip().startswith("pip install")
    assert "observe(" in readme_blocks[1] and "make" not in readme_blocks[1]


# -- public docstrings: what a condition means in the body, the paper's numbers in References ----------
DOCSTRING_REFERENCE = re.compile(
    r"\b(?:Theorem|Thm|Lemma|Hypothes[ie]s|Assumption|Proposition|Prop|Corollary|Algorithm)s?\.? \d"
    r"|(?<![\w\])\[\"'`.])\(\d{1,3}[a-z]?\)"
    r"|\b[Ee]qs?\. ?\(?\d"
    r"|(?i:\bseeds? 00\d)|\bH-matrix\b|U2'g"
)
"""A paper-internal reference in a docstring: a numbered theorem, lemma, hypothesis, assumption,
proposition, corollary or algorithm, an equation number ("(68)", "eq. (39)"; not a call such as
``x(0)`` nor a quoted option value such as ``"(26)"``), a paper's file number, or a paper's symbol."""
SECTION_RULE = re.compile(r"^-{3,}$")
CITATION_PARAGRAPH = re.compile(r"^\s*\*\*References?\.\*\*")
DOCSTRING_ALLOWED_PREFIXES = {
    "intervalobs.reproduce.": "the reproductions of the papers' examples: each maps a paper's printed "
    "design and numbers to the code, as docs/paper-notes.md does",
}
"""Public objects whose docstrings may keep paper-internal references in their body, and why."""


def _citing_sections(doc: str) -> str:
    """A docstring without its ``References`` section, a ``Notes`` section that cites one of the five
    papers by its short name, and any paragraph opened by ``**Reference.**``: the text to scan."""
    from intervalobs.references import PAPERS

    shorts = [paper.short for paper in PAPERS.values()]
    sections: list[tuple[str, list[str]]] = [("", [])]
    lines = doc.splitlines()
    for index, line in enumerate(lines):
        if line.strip() and index + 1 < len(lines) and SECTION_RULE.match(lines[index + 1].strip()):
            sections.append((line.strip(), []))
        sections[-1][1].append(line)
    kept = []
    for name, body in sections:
        text = "\n".join(body)
        cites = any(short in " ".join(text.split()) for short in shorts)
        if name == "References" or (name == "Notes" and cites):
            continue
        kept.append(text)
    paragraphs = re.split(r"\n\s*\n", "\n".join(kept))
    return "\n\n".join(p for p in paragraphs if not CITATION_PARAGRAPH.match(p))


def docstring_references(doc: str) -> list[str]:
    """The paper-internal references in a docstring's body (outside its citing sections).

    Parameters
    ----------
    doc : str
        A cleaned docstring (:func:`inspect.getdoc`).

    Returns
    -------
    list of str
        Each offending reference, in order.
    """
    return [m.group(0) for m in DOCSTRING_REFERENCE.finditer(_citing_sections(doc))]


def _public_docstrings() -> dict[str, str]:
    """The docstring of every public class, function, method and property, by dotted name."""
    from public_api import public_objects

    found = {}
    for name, obj in public_objects().items():
        target = obj.fget if isinstance(obj, property) else obj
        found[name] = inspect.getdoc(target) or ""
    return found


def _allowed(name: str) -> bool:
    return any(name.startswith(p) for p in DOCSTRING_ALLOWED_PREFIXES)


def test_public_docstrings_keep_the_paper_in_their_references() -> None:
    offending = {
        name: refs
        for name, doc in _public_docstrings().items()
        if not _allowed(name) and (refs := docstring_references(doc))
    }
    lines = [f"{name}: {refs}" for name, refs in sorted(offending.items())]
    assert not offending, (
        "say what the condition means for the user's system; move the paper's numbers into a "
        "References section:\n  " + "\n  ".join(lines)
    )


@pytest.mark.parametrize(
    ("doc", "expected"),
    [
        ("Gain of Theorem 4.2 and (34).\n\nNotes\n-----\nA plain note.", ["Theorem 4", "(34)"]),
        ('The observer of eqs. (39)-(40); x(0) and ``"(26)"`` are fine.', ["eqs. (3", "(40)"]),
        ("Bounds that hold for every noise.\n\nReferences\n----------\nThe paper, Lemma 3 and (8).", []),
        ("Bounds.\n\nNotes\n-----\nRotondo et al., (63)-(66).", []),
        ("Bounds.\n\nNotes\n-----\nFrom (63)-(66).", ["(63)", "(66)"]),
        ("Bounds.\n\n**Reference.** Khajenejad & Yong, Lemma 4.\n\nMore.", []),
        ("Uses the H-matrix of seed 003.", ["H-matrix", "seed 003"]),
    ],
    ids=["body", "equations", "references", "notes-citing", "notes-not-citing", "paragraph", "symbols"],
)
def test_the_docstring_scan_finds_a_paper_reference(doc: str, expected: list[str]) -> None:
    assert docstring_references(doc) == expected


def test_every_citation_is_complete_or_says_what_is_unverified() -> None:
    from intervalobs.references import PAPERS

    for paper in PAPERS.values():
        assert set(paper.unverified) <= {"authors", "title", "venue", "year", "DOI"}, paper.short
        given = "doi:" in paper.citation
        assert given != ("DOI" in paper.unverified), f"{paper.short}: give the DOI or declare it unverified"
