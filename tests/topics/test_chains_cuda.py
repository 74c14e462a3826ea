"""The CUDA labelling kernels give the CPU kernels' bytes: under numba's CUDA simulator, on any machine.

The simulator is chosen by ``NUMBA_ENABLE_CUDASIM=1`` before numba.cuda is first imported,
so each case runs in a process of its own (``cuda_cases.py``); the rest of the suite keeps
numba as it is. Skipped where numba-cuda is not installed (it is in the ``test`` extra).
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest
from cuda_cases import CASES

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("numba_cuda") is None, reason="numba-cuda (the extra curiosity-cli[cuda]) is not installed"
)
SCRIPT = Path(__file__).with_name("cuda_cases.py")


@pytest.mark.slow
@pytest.mark.parametrize("case", list(CASES))
def test_the_simulated_gpu_gives_the_cpus_bytes(case):
    env = {**os.environ, "NUMBA_ENABLE_CUDASIM": "1"}
    done = subprocess.run(
        [sys.executable, str(SCRIPT), case], env=env, capture_output=True, text=True, timeout=600,
        cwd=Path(__file__).resolve().parents[2],
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"{case}: the same bytes" in done.stdout
