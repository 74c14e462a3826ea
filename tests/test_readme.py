"""The README's two commands are the project's contract with a newcomer and with CI."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

#: The repository this test checks.
PROJECT_ROOT = Path(__file__).resolve().parents[1]
README = (PROJECT_ROOT / "README.md").read_text()
COMMANDS = re.findall(r"```bash\n(.+?)\n```", README)


def test_readme_gives_exactly_two_commands():
    assert len(COMMANDS) == 2
    assert all("\n" not in c and "python3 -m venv .venv" in c for c in COMMANDS)


def test_ci_runs_the_readme_test_command_verbatim():
    ci_lines = (PROJECT_ROOT / ".ci" / "run").read_text().strip().splitlines()
    assert ci_lines[-1] == COMMANDS[1]
    assert "pytest" in COMMANDS[1] and "[test]" in COMMANDS[1]


def test_the_test_commands_worker_processes_come_with_the_test_extra():
    import tomllib

    test_extra = tomllib.loads((PROJECT_ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]["test"]
    assert COMMANDS[1].endswith("pytest -n 2")  # -n is pytest-xdist's
    assert any(re.match(r"pytest-xdist\b", requirement) for requirement in test_extra), test_extra


def test_readme_pictures_exist():
    pictures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", README)
    assert "docs/datasets.png" in pictures and "docs/specification-curve-seeds-0-1-2.png" in pictures
    assert all((PROJECT_ROOT / picture).is_file() for picture in pictures), pictures


def test_readme_links_to_files_that_exist():
    targets = [t for t in re.findall(r"\]\(([^)]+)\)", README) if "://" not in t]
    assert "docs/ARCHITECTURE.md" in targets and "docs/GUIDE.md" in targets
    assert all((PROJECT_ROOT / t.split("#")[0]).exists() for t in targets), targets


def test_the_guide_links_to_files_and_headings_that_exist():
    import unicodedata

    docs = PROJECT_ROOT / "docs"
    guide = (docs / "GUIDE.md").read_text()

    def anchor(heading: str) -> str:  # as GitHub makes them: lower case, punctuation dropped, spaces as hyphens
        text = unicodedata.normalize("NFKC", heading.strip().lower())
        return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")

    anchors = {anchor(h) for h in re.findall(r"^#+ (.+)$", guide, re.M)}
    targets = [t for t in re.findall(r"\]\(([^)]+)\)", guide) if "://" not in t]
    assert "specification-curve.png" in targets and "../README.md" in targets
    assert all((docs / t.split("#")[0]).exists() for t in targets if not t.startswith("#")), targets
    readme_anchors = re.findall(r"\]\(docs/GUIDE\.md#([^)]+)\)", README)
    assert readme_anchors and all(a in anchors for a in readme_anchors), readme_anchors


@pytest.mark.slow
def test_the_python_example_runs_as_written(tmp_path, monkeypatch):
    (example,) = re.findall(r"```python\n(.+?)\n```", README, re.S)
    monkeypatch.chdir(tmp_path)  # results/ of the current folder, as a notebook's
    printed = subprocess.run(
        [sys.executable, "-c", example], capture_output=True, text=True, timeout=600,
        env={**os.environ, "CURIOSITY_CACHE": str(tmp_path / "cache")},
    )
    assert printed.returncode == 0, printed.stderr
    assert "topic-perplexity" in printed.stdout and "20 steps; Φ_p at 20 steps has" in printed.stdout
    assert (tmp_path / "results" / "tiny" / "mi.csv").is_file()
    assert (tmp_path / "cache" / "stores").is_dir()  # word stores in the user cache, not beside the results
