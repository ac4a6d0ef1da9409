"""The shared validation helpers give exact, named messages."""

import numpy as np
import pytest

from crankbench.measure._atomic import atomic_path
from crankbench.predict._toml import load_toml
from crankbench.predict._validate import (check_finite_array, check_int, check_option, check_positive,
                               check_range, require)
from crankbench.predict.errors import CrankbenchError, MissingDependencyError, ModelError


def test_check_positive_names_argument():
    assert check_positive(2, "crank_radius") == 2.0
    with pytest.raises(ValueError, match=r"^crank_radius=-1 must be > 0$"):
        check_positive(-1, "crank_radius")
    with pytest.raises(ValueError, match=r"^crank_radius=nan must be finite$"):
        check_positive(float("nan"), "crank_radius")
    with pytest.raises(ValueError, match=r"^crank_radius='a' must be a real number$"):
        check_positive("a", "crank_radius")


def test_check_range_and_int():
    assert check_range(0.3, "lam", 0, 1) == 0.3
    with pytest.raises(ValueError, match=r"^lam=1.5 must lie in \(0, 1\)$"):
        check_range(1.5, "lam", 0, 1, inclusive=(False, False))
    assert check_int(3.0, "n") == 3
    with pytest.raises(ValueError, match=r"^n=2.5 must be an integer$"):
        check_int(2.5, "n")
    with pytest.raises(ValueError, match=r"^n=0 must be >= 1$"):
        check_int(0, "n", minimum=1)


def test_check_option_suggests():
    with pytest.raises(ValueError, match=r"amplitude='pek' is not one of 'peak', 'rms'.*did you mean 'peak'"):
        check_option("pek", "amplitude", ["peak", "rms"])


def test_check_finite_array_points_at_first_bad_value():
    with pytest.raises(ValueError, match=r"^x contains 2 NaN/inf value\(s\), first at index 1$"):
        check_finite_array([0.0, np.nan, np.inf], "x")


def test_error_family_is_valueerror_and_ours():
    assert issubclass(ModelError, ValueError) and issubclass(ModelError, CrankbenchError)
    with pytest.raises(MissingDependencyError, match=r"pip install 'crankbench\[pdf\]'"):
        require("no_such_module_xyz", extra="pdf", feature="PDF reports")


def test_toml_table_names_file_and_key(tmp_path):
    f = tmp_path / "e.toml"
    f.write_text("[engine]\ncrank_radius = -0.04\nrod_lenght = 0.15\n")
    engine = load_toml(f).table("engine")
    with pytest.raises(ModelError, match=r"e\.toml: engine\.crank_radius = -0\.04 must be > 0$"):
        engine.positive("crank_radius")
    engine.number("rod_length", 0.15)
    with pytest.raises(ModelError, match=r"engine\.rod_lenght is not a known key \(did you mean 'rod_length'\?\)"):
        engine.check_unknown()
    bad = tmp_path / "bad.toml"
    bad.write_text("[engine\n")
    with pytest.raises(ModelError, match=r"bad\.toml: not valid TOML"):
        load_toml(bad)


def test_atomic_path_refuses_overwrite_and_leaves_no_partial(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(FileExistsError, match=r"out\.txt exists; pass overwrite=True to replace it"):
        with atomic_path(target):
            pass
    with pytest.raises(RuntimeError):
        with atomic_path(target, overwrite=True) as tmp:
            tmp.write_text("half")
            raise RuntimeError("crash mid-write")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def test_atomic_output_gets_ordinary_permissions(tmp_path):
    import os
    umask = os.umask(0o022)
    try:
        with atomic_path(tmp_path / "r.txt") as tmp:
            tmp.write_text("x")
    finally:
        os.umask(umask)
    assert oct((tmp_path / "r.txt").stat().st_mode & 0o777) == oct(0o644)
