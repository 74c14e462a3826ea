"""The kernel cache folder follows the kernel sources, so an edit never runs stale machine code."""

from __future__ import annotations

import os
import subprocess
import sys

from curiosity_cli._numba import kernel_sources_hash


def test_the_hash_changes_with_any_private_module_and_only_those(tmp_path):
    (tmp_path / "topics").mkdir()
    (tmp_path / "topics" / "_sampler.py").write_text("def draw(): return 1\n")
    (tmp_path / "topics" / "_gibbs_kernels.py").write_text("from ._sampler import draw\n")
    (tmp_path / "topics" / "model.py").write_text("x = 1\n")
    (tmp_path / "topics" / "__init__.py").write_text("")
    before = kernel_sources_hash(tmp_path)
    # a public module or a package's __init__ does not change the kernels
    (tmp_path / "topics" / "model.py").write_text("x = 2\n")
    (tmp_path / "topics" / "__init__.py").write_text("# docs\n")
    assert kernel_sources_hash(tmp_path) == before
    # a called kernel in another file does (numba's own cache check would miss this one)
    (tmp_path / "topics" / "_sampler.py").write_text("def draw(): return 2\n")
    assert kernel_sources_hash(tmp_path) != before


def test_numba_caches_into_the_folder_of_these_sources():
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    code = (
        "import numba\n"  # numba first, as any module might: the folder must still be ours
        "import curiosity_cli._numba as n, numba.core.config as c\n"
        "print(c.CACHE_DIR == str(n.cache_dir()), n.cache_dir().name == 'numba-' + n.kernel_sources_hash())\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert result.stdout.split() == ["True", "True"]
