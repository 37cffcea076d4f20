"""The lookup tables the add-on ships (addon/reference/tables.npz) are what scripts/build_tables.py computes
from their definitions in addon/reference/multiscatter.py, and the engine reads them instead of computing
them at its first render."""

from __future__ import annotations

import numpy as np
import pytest

from addon.reference import ltc, multiscatter

#: The area lights' LTC fits take two minutes: tests/test_ltc.py refits sample cells of them
#: instead, and recomputes the sphere table whole.
LTC_TABLES = {f"ltc_{ndf}" for ndf in ltc.NDFS} | {"ltc_sphere"}


@pytest.fixture(scope="module")
def computed():
    return multiscatter.compute_all()


def test_the_shipped_file_holds_every_table(computed):
    shipped = multiscatter._shipped()
    assert sorted(shipped) == sorted(set(computed) | LTC_TABLES), "run scripts/build_tables.py"


def test_shipped_tables_equal_what_the_script_computes(computed):
    shipped = multiscatter._shipped()
    worst = {}
    for name, table in computed.items():
        assert shipped[name].shape == table.shape and shipped[name].dtype == table.dtype, name
        worst[name] = float(np.abs(shipped[name].astype(np.float64) - table).max())
    # float32 tables from deterministic numpy: equal up to the last bits another machine's math
    # library may round differently
    bad = {k: v for k, v in worst.items() if v > 1e-6}
    assert not bad, f"shipped tables differ from the computation (run scripts/build_tables.py): {bad}"


def test_the_engine_reads_the_shipped_tables():
    shipped = multiscatter._shipped()
    assert multiscatter.albedo_table("GGX", "SMITH_CORRELATED") is shipped["albedo_GGX_SMITH_CORRELATED"]
    assert multiscatter.principled_s_table() is shipped["principled_s"]
    assert multiscatter.split_sum_table("BECKMANN", "VCAVITY") is shipped["split_BECKMANN_VCAVITY"]
    assert multiscatter.average_albedo() is shipped["average_albedo"]
    assert ltc.ltc_table("GGX") is shipped["ltc_GGX"] and ltc.sphere_table() is shipped["ltc_sphere"]


def test_a_size_not_shipped_is_computed():
    table = multiscatter.albedo_table("GGX", "SMITH_CORRELATED", size=8)
    assert table.shape == (8, 8)
    np.testing.assert_array_equal(table, multiscatter.compute_albedo_table("GGX", "SMITH_CORRELATED", 8))
