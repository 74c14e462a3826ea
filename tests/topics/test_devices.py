"""The one table of label devices (issue 47): config's names, ``auto``, and each device's engine."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from curiosity_cli.config import LABEL_DEVICES
from curiosity_cli.errors import ParameterError
from curiosity_cli.topics.chains import FrozenChains
from curiosity_cli.topics.engines import CpuEngine
from curiosity_cli.topics.devices import AUTO, AUTO_FALLBACK, AUTO_PREFERS, DEVICES, Device, DeviceError, resolve_device

ONE_CELL = dict(words=[3, 3, 0], cells=[0, 0, 0], neighbours=np.array([[-1, -1, -1, -1]], np.int32))


def present(monkeypatch, *names: str, missing=None) -> None:
    """Make ``names``' devices present here (``missing=None``) or missing for the reason ``missing``."""
    for name in names:
        monkeypatch.setitem(DEVICES, name, dataclasses.replace(DEVICES[name], missing=lambda: missing))


def test_every_name_config_accepts_is_resolved_by_the_table(monkeypatch):
    assert (*DEVICES, AUTO) == LABEL_DEVICES
    assert all(name == device.name for name, device in DEVICES.items())
    present(monkeypatch, *DEVICES)
    for name in LABEL_DEVICES:
        assert resolve_device(name) in DEVICES
    with pytest.raises(DeviceError, match=r"label.device: got 'gpu', expected one of cpu, cuda, auto"):
        resolve_device("gpu")


def test_auto_takes_the_first_device_present_else_the_cpu_saying_why_once(monkeypatch, capsys):
    assert AUTO_PREFERS == ("cuda",) and AUTO_FALLBACK == "cpu"
    present(monkeypatch, "cuda")
    assert resolve_device("auto") == "cuda"
    assert capsys.readouterr().err == ""
    present(monkeypatch, "cuda", missing="no CUDA GPU was found (none here)")
    assert resolve_device("auto", parameter="x.device") == "cpu"
    assert capsys.readouterr().err == "x.device is auto: labelling on the CPU, as no CUDA GPU was found (none here)\n"
    with pytest.raises(DeviceError, match=r"^x.device: cuda, but no CUDA GPU was found \(none here\)$"):
        resolve_device("cuda", parameter="x.device")
    assert resolve_device("cpu") == "cpu" and capsys.readouterr().err == ""


def test_a_device_names_its_own_engine_so_none_runs_on_the_cpu_unsaid():
    with pytest.raises(TypeError, match="engine"):
        Device("tpu", block_chains=16, parallel_blocks=True, frees_cores=False, shown="the TPU", announced=True,
               missing=lambda: None)
    engines = [device.engine for device in DEVICES.values()]
    assert len(set(engines)) == len(engines), "two devices share an engine: one of them runs elsewhere than it says"
    assert DEVICES["cpu"].engine is CpuEngine


def test_the_chains_run_on_the_engine_the_table_names_and_refuse_a_name_it_lacks(monkeypatch):
    made = []

    class Recording(CpuEngine):
        def __init__(self, *args):
            made.append(args)
            super().__init__(*args)

    monkeypatch.setitem(DEVICES, "elsewhere", dataclasses.replace(DEVICES["cpu"], name="elsewhere", engine=Recording))
    chains = FrozenChains(**ONE_CELL, n_topics=2, vocabulary_size=4, alpha=0.1, beta=0.1, device="elsewhere")
    assert len(made) == 1 and chains.device == "elsewhere"
    monkeypatch.delitem(DEVICES, "elsewhere")
    with pytest.raises(ParameterError, match=r"^device: got 'elsewhere', expected one of cpu, cuda$"):
        FrozenChains(**ONE_CELL, n_topics=2, vocabulary_size=4, alpha=0.1, beta=0.1, device="elsewhere")
