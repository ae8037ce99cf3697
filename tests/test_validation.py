"""The boundary checks (validation.py): every bad argument raises a named IntervalObserverError subclass
whose one-line message names the argument, the expected and the actual value."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from intervalobs import IntervalObserver, LTISystem
from intervalobs.design.regions import place_in_disks
from intervalobs.errors import ArgumentError, ArgumentTypeError, FileError, IntervalObserverError
from intervalobs.examples import spring_mass
from intervalobs.validation import (
    as_array,
    as_choice,
    as_count,
    as_fraction,
    as_input_path,
    as_matrix,
    as_output_folder,
    as_positive,
    as_signal,
    check_both_or_neither,
)

C = np.array([[1.0, 0.0]])

# (call, error class, message pattern): each is refused before any computation
CASES: dict[str, tuple[Callable[[], Any], type[Exception], str]] = {
    "complex-A": (lambda: LTISystem([[0.0, 1.0], [-1.0, 1j]], C), ArgumentTypeError,
                  r"^A: expected real numbers, got complex values \(largest imaginary part 1\)$"),
    "complex-y": (lambda: as_signal("y", np.zeros((3, 1)) + 0.5j, 3, 1), ArgumentTypeError,
                  r"^y: expected real numbers, got complex values"),
    "text-matrix": (lambda: as_matrix("C", [["1", "0"]]), ArgumentTypeError, r"^C: expected real numbers, got text"),
    "none-array": (lambda: as_array("t", None), ArgumentTypeError, r"^t: expected a numeric array, got None$"),
    "ragged": (lambda: as_array("y", [[1.0], [1.0, 2.0]]), ArgumentTypeError, r"^y: expected a numeric array"),
    "dt-text": (lambda: LTISystem([[0.5]], [[1.0]], dt="0.1"), ArgumentTypeError,
                r"^dt: expected a positive sampling period or None, got '0.1' \(str\)$"),
    "dt-negative": (lambda: LTISystem([[0.5]], [[1.0]], dt=-1.0), ArgumentError,
                    r"^dt: expected a positive sampling period or None, got -1$"),
    "dt-inf": (lambda: LTISystem([[0.5]], [[1.0]], dt=np.inf), ArgumentError, r"^dt: expected .*, got inf$"),
    "h-text": (lambda: IntervalObserver.design(spring_mass.system(), spring_mass.bounds(), h="0.1"), ArgumentTypeError,
               r"^h: expected a positive step for a continuous-time system, got '0.1' \(str\)$"),
    "h-negative": (lambda: IntervalObserver.design(spring_mass.system(), spring_mass.bounds(), h=-0.1), ArgumentError,
                   r"^h: expected a positive step for a continuous-time system, got -0.1$"),
    "design-method": (
        lambda: IntervalObserver.design(spring_mass.system(), spring_mass.bounds(), h=0.1, method="bogus"),
        ArgumentError, r"^method: expected one of 'tube', 'framer', got 'bogus'$",
    ),
    "region-objective": (lambda: place_in_disks([[0.0]], [[1.0]], [(-1.0, 0.5)], objective="x"), ArgumentError,
                         r"^objective: expected one of 'min_gain', 'center', got 'x'$"),
    "count-zero": (lambda: as_count("runs", 0), ArgumentError, r"^runs: expected an integer >= 1, got 0$"),
    "count-float": (lambda: as_count("runs", 2.0), ArgumentTypeError, r"^runs: expected an integer >= 1, got 2.0$"),
    "count-bool": (lambda: as_count("runs", True), ArgumentTypeError, r"got True \(bool\)$"),
    "fraction-percent": (lambda: as_fraction("level", 10), ArgumentError,
                         r"^level: expected a fraction in \[0, 1\) \(0.05 means ±5 %\), got 10$"),
    "fraction-nan": (lambda: as_fraction("level", float("nan")), ArgumentError, r"got nan$"),
    "positive-zero": (lambda: as_positive("h", 0.0), ArgumentError, r"^h: expected a positive number, got 0$"),
    "choice": (lambda: as_choice("kind", "c", ("a", "b")), ArgumentError, r"^kind: expected one of 'a', 'b', got 'c'$"),
    "one-of-a-pair": (lambda: check_both_or_neither(("lo", None), ("hi", 1.0)), ArgumentError,
                      r"^lo, hi: expected both or neither, got hi without lo$"),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(CASES), ids=sorted(CASES))
def test_bad_argument_raises_a_named_error_without_warnings(case: str) -> None:
    call, error, pattern = CASES[case]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # e.g. NumPy's ComplexWarning must not come first
        with pytest.raises(error, match=pattern) as caught:
            call()
    assert isinstance(caught.value, IntervalObserverError)
    assert "\n" not in str(caught.value)


def test_errors_subclass_the_builtin_kinds() -> None:
    """Callers that catch ValueError/TypeError/OSError keep working (python-control's convention)."""
    assert issubclass(ArgumentError, ValueError) and issubclass(ArgumentTypeError, TypeError)
    assert issubclass(FileError, OSError)


def test_complex_with_zero_imaginary_part_loses_nothing_and_is_accepted() -> None:
    np.testing.assert_array_equal(as_array("A", np.array([[1.0 + 0j, 2.0]])), [[1.0, 2.0]])


def test_scalar_checks_accept_and_return_good_values() -> None:
    assert as_count("seed", np.int64(0), minimum=0) == 0 and isinstance(as_count("runs", np.int64(3)), int)
    assert as_fraction("level", 0.0) == 0.0 and as_fraction("level", np.float64(0.5)) == 0.5
    assert as_positive("dt", 1) == 1.0
    check_both_or_neither(("lo", None), ("hi", None))
    check_both_or_neither(("lo", 0.0), ("hi", 1.0))


def test_output_folder_is_checked_without_creating_anything(tmp_path) -> None:
    target = tmp_path / "a" / "b"
    assert as_output_folder("out", target) == target and list(tmp_path.iterdir()) == []
    (tmp_path / "file").write_text("x")
    with pytest.raises(
        FileError, match=r"^out: expected a folder to write into, got '.*file/sub' \(.*file is a file\)$"
    ):
        as_output_folder("out", tmp_path / "file" / "sub")


def test_output_folder_must_be_writable(tmp_path) -> None:
    import os

    if not os.path.isdir("/proc"):
        pytest.skip("needs /proc (a folder nobody can create files in)")
    with pytest.raises(
        FileError, match=r"^out: expected a writable folder, got '/proc/x' \(cannot create a file in /proc\)$"
    ):
        as_output_folder("out", "/proc/x")


def test_input_paths_must_exist(tmp_path) -> None:
    (tmp_path / "file.txt").write_text("x")
    with pytest.raises(FileError, match=r"^path: expected an existing file, got '.*missing.npz' \(no such file\)$"):
        as_input_path("path", tmp_path / "missing.npz")
    with pytest.raises(FileError, match=r"\(a folder\)$"):
        as_input_path("path", tmp_path)
    with pytest.raises(FileError, match=r"\(a file\)$"):
        as_input_path("results", tmp_path / "file.txt", "folder")
    with pytest.raises(FileError, match=r"^results: expected an existing folder, got '.*nope' \(no such folder\)$"):
        as_input_path("results", tmp_path / "nope", "folder")
    assert as_input_path("results", tmp_path, "folder") == tmp_path
