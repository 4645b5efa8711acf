import json
import pathlib

import pytest

from exact_khk import exact_arith_names

DATA = pathlib.Path(__file__).parent / "data"

#: every installed exact rational arithmetic; tests parametrised over it
EXACT = exact_arith_names()


@pytest.fixture(scope="session")
def golden():
    return json.loads((DATA / "golden_orbits.json").read_text())["cases"]
