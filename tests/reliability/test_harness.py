"""The reliability harness itself: it passes a clean error and catches a traceback."""

from __future__ import annotations

import pytest
from cli_cases import Outcome, assert_clean_error, run_cli


def test_a_missing_config_is_one_clean_line(tmp_path):
    outcome = run_cli(["explore", "missing.yaml"], cwd=tmp_path)
    assert_clean_error(outcome, "missing.yaml")


def test_the_harness_catches_a_traceback_and_two_error_lines():
    with pytest.raises(AssertionError, match="Traceback"):
        assert_clean_error(Outcome(1, "", "Traceback (most recent call last):\nError: x"), "x")
    with pytest.raises(AssertionError, match="one Error line"):
        assert_clean_error(Outcome(1, "", "Error: a\nError: b"), "a")
