"""Fixtures of the gbmgen tests."""
import pytest
from _gbmgen_builds import table_4_1_path

from gbmgen.table import read_table


@pytest.fixture(scope="module")
def table41():
    return read_table(table_4_1_path())
