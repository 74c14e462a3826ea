"""The package as a user installs it: a wheel built from this checkout's sdist, installed into a
fresh virtual environment, run from an empty folder outside the checkout.

The fresh environment gets the wheel itself, and its dependencies from this test's
environment (one ``.pth`` line), so the test needs no download beyond the build backend
and proves what the wheel carries: every module, the shipped configs, vocabularies and
embedded maps.
"""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import pytest

CHECKOUT = Path(__file__).resolve().parents[1]
#: A small grid on an embedded map: enough to prove a run reads the shipped data and writes where it should.
TINY = [
    "--set", "datasets=[aerial-mosaic]", "--set", "explore.restarts=1", "--set", "explore.path_length=10",
    "--set", "explore.checkpoints=[10]", "--set", "explore.weight_functions=[random-walk]",
    "--set", "explore.samples_per_step=2000", "--jobs", "1",
]


def _files(root: Path) -> dict[Path, int]:
    return {p: p.stat().st_mtime_ns for p in root.rglob("*") if p.is_file()}


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[Path, Path]:
    """``(the wheel, the fresh environment's site-packages)``."""
    root = tmp_path_factory.mktemp("packaging")
    built = subprocess.run(
        # the sdist, then the wheel from it: both must carry the shipped files
        [sys.executable, "-m", "build", "--outdir", str(root / "dist"), str(CHECKOUT)],
        capture_output=True, text=True, timeout=600,
    )
    assert built.returncode == 0, built.stdout[-2000:] + built.stderr[-2000:]
    (wheel,) = (root / "dist").glob("curiosity_cli-*.whl")
    env = root / "env"
    venv.create(env, with_pip=True)
    python = env / "bin" / "python"
    site = Path(subprocess.run(
        [python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], capture_output=True, text=True,
        check=True,
    ).stdout.strip())
    # the dependencies, not this checkout's package: a path line runs no .pth of the directory it adds
    (site / "dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    done = subprocess.run(
        [python, "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(wheel)], capture_output=True, text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return wheel, site


@pytest.mark.slow
def test_the_installed_wheel_runs_from_any_folder_and_writes_only_there_and_in_the_cache(installed, tmp_path):
    wheel, site = installed
    work, cache = tmp_path / "work", tmp_path / "cache"
    work.mkdir()
    env = {**{k: v for k, v in os.environ.items() if not k.startswith(("CURIOSITY_", "NUMBA_CACHE"))},
           "CURIOSITY_CACHE": str(cache)}
    curiosity = site.parent.parent.parent / "bin" / "curiosity"
    before = _files(site)

    def run(*args: str) -> str:
        done = subprocess.run([curiosity, *args], cwd=work, env=env, capture_output=True, text=True, timeout=900)
        assert done.returncode == 0, f"curiosity {' '.join(args)}:\n{done.stdout}\n{done.stderr}"
        return done.stdout

    where = subprocess.run(
        [site.parent.parent.parent / "bin" / "python", "-c", "import curiosity_cli; print(curiosity_cli.__file__)"],
        cwd=work, env=env, capture_output=True, text=True, check=True,
    ).stdout
    assert Path(where.strip()).is_relative_to(site), f"not the wheel's package: {where}"
    listed = run("datasets", "list")
    assert all(name in listed for name in ("aerial-mosaic", "geonrw-essen", "reef-mosaic", "sentinel-coast", "zurich-zh17"))
    for name in ("aerial-mosaic", "geonrw-essen", "reef-mosaic", "sentinel-coast"):  # every embedded map's three files
        shipped = site / "curiosity_cli" / "shipped" / "data" / "maps" / name
        assert sorted(p.name for p in shipped.iterdir()) == ["image.png", "labels.png", "legend.yaml"], name
    assert "name: quick" in run("config", "show", "quick")
    assert "words" in run("extract", "aerial-mosaic")
    run("explore", "quick", *TINY)
    assert (work / "results" / "quick" / "runs" / "aerial-mosaic" / "random-walk" / "restart-000" / "run.json").is_file()
    assert list((cache / "stores").glob("aerial-mosaic-*.npz")), "the word store is not in the user cache"
    assert _files(site) == before, "something was written into site-packages"
    assert sorted(p.name for p in work.iterdir()) == ["results"]
    assert wheel.stat().st_size < 20_000_000  # the embedded maps are most of it
