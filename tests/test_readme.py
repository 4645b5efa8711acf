"""The README's Python examples run as doctests."""

import doctest
import pathlib


def test_readme_examples():
    readme = pathlib.Path(__file__).resolve().parent.parent / "README.md"
    result = doctest.testfile(str(readme), module_relative=False, optionflags=doctest.ELLIPSIS)
    assert result.attempted >= 5
    assert result.failed == 0


def test_readme_states_the_default_runs_verdict():
    """The verdict the README quotes for `exact-khk certify` is the one the default run gives
    (its counts of claims and controls: a change in the default checks must change the text)."""
    import re

    from exact_khk import certify

    readme = (pathlib.Path(__file__).resolve().parent.parent / "README.md").read_text(encoding="utf-8")
    m = re.search(r"`(VALID: all \d+ claims hold and all \d+ negative controls fail) \(\.\.\.\)`", readme)
    assert m, "README no longer quotes the default run's verdict"
    verdict = certify().verdict()
    assert verdict.startswith(m.group(1) + " ("), verdict


def test_readme_is_short():
    """A newcomer reads it in minutes: about 200 lines (details live in docs/)."""
    readme = pathlib.Path(__file__).resolve().parent.parent / "README.md"
    assert len(readme.read_text(encoding="utf-8").splitlines()) <= 220
