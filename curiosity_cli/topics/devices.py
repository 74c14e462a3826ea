"""The devices labelling chains run on, in one table, and ``label.device`` made one of them.

:class:`~curiosity_cli.topics.chains.FrozenChains` runs on every device of
:data:`DEVICES` with the same bytes (``topics/chains.py``): the CPU, or a CUDA GPU, which
needs numba-cuda (the optional extra ``curiosity-cli[cuda]``) and a GPU that numba sees.
``label.device`` names one of them, or ``auto``: the first of :data:`AUTO_PREFERS` present
here, else the CPU, saying once why.

To add a device, write its engine (the interface in ``topics/chains.py``'s docstring), give
it a :class:`Device` here and put its name in :data:`curiosity_cli.config.LABEL_DEVICES`,
the one list of the names a config may give: the config layer checks the names it loads
without importing this stage, and this module refuses to load unless its table holds
exactly those names. The chains, the label stage and ``curiosity reproduce`` ask a
device's fields, never its name.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from curiosity_cli.config import LABEL_DEVICES as DEVICE_CHOICES
from curiosity_cli.errors import CuriosityError
from curiosity_cli.files import note
from curiosity_cli.topics.engines import CpuEngine, CudaEngine

#: How a user gets numba-cuda.
CUDA_EXTRA = "pip install 'curiosity-cli[cuda]' (from a checkout: pip install -e '.[cuda]')"
#: The name that asks for the first device present (:func:`resolve_device`).
AUTO = "auto"


class DeviceError(CuriosityError):
    """A device was asked for that this machine cannot label on."""


@dataclass(frozen=True)
class Device:
    """A device the chains can run on, and how the label stage uses it.

    Attributes
    ----------
    name : str
        Its name in ``label.device``.
    engine : type
        What holds a block's chains there and advances them (the interface:
        ``topics/chains.py``'s docstring); :class:`~curiosity_cli.topics.chains.FrozenChains`
        runs no other.
    block_chains : int or None
        The most chains it wants in one block (a task); None: every chain of a map.
    parallel_blocks : bool
        Its blocks run side by side, one per worker, so a map's chains are cut to keep
        every worker busy; False: it takes one block at a time, planned as for one worker.
    frees_cores : bool
        Its blocks leave the CPU's cores free, so batch references are computed beside them
        in the label stage, never beside the exploration, which they would slow.
    shown : str
        How messages name it.
    announced : bool
        Whether the label stage's progress line says where it labels (not where it
        labels by default).
    missing : callable
        ``missing()``: why it cannot label on this machine, in words; None when it can.
    """

    name: str
    engine: type
    block_chains: int | None
    parallel_blocks: bool
    frees_cores: bool
    shown: str
    announced: bool
    missing: Callable[[], str | None]


def cuda_missing() -> str | None:
    """Why labelling cannot run on a CUDA GPU here, in words; None when it can."""
    from curiosity_cli._numba import import_cuda

    try:
        import_cuda()
    except ImportError as exc:
        return f"it needs numba-cuda, the extra curiosity-cli[cuda], which is not installed ({exc}): {CUDA_EXTRA}"
    from curiosity_cli.topics._chain_kernels_cuda import gpu_available

    ready, why = gpu_available()
    return None if ready else f"no CUDA GPU was found ({why})"


def _on_every_machine() -> None:
    """The CPU is never missing."""


#: Every device the chains run on, by name, in the order messages list them.
DEVICES = {
    device.name: device
    for device in (
        # past 16 chains a block gained no more on the 2-core AVX2 machine (scripts/bench_label.py),
        # and smaller blocks share out better
        Device("cpu", CpuEngine, block_chains=16, parallel_blocks=True, frees_cores=False, shown="the CPU",
               announced=False, missing=_on_every_machine),
        # a GPU's time per chain falls until a few hundred chains (docs/PERFORMANCE.md)
        Device("cuda", CudaEngine, block_chains=None, parallel_blocks=False, frees_cores=True, shown="the GPU",
               announced=True, missing=cuda_missing),
    )
}
#: What ``auto`` takes: the first of these devices present here, else :data:`AUTO_FALLBACK`.
AUTO_PREFERS = ("cuda",)
#: What ``auto`` takes when no device it prefers is present: on every machine.
AUTO_FALLBACK = "cpu"
if (*DEVICES, AUTO) != DEVICE_CHOICES or not {*AUTO_PREFERS, AUTO_FALLBACK} <= set(DEVICES):
    raise ImportError(
        f"topics.devices: devices {(*DEVICES, AUTO)} and auto's {(*AUTO_PREFERS, AUTO_FALLBACK)} "
        f"are not config.LABEL_DEVICES {DEVICE_CHOICES}"
    )


def resolve_device(device: str, *, parameter: str = "label.device") -> str:
    """The device ``device`` asks for on this machine: a name in :data:`DEVICES`.

    Parameters
    ----------
    device : str
        A name in :data:`DEVICE_CHOICES`: a device, or ``auto``.
    parameter : str
        The setting's name, for the messages.

    Returns
    -------
    str
        The device's name; ``auto`` with none of :data:`AUTO_PREFERS` present notes once,
        on stderr, why it labels on :data:`AUTO_FALLBACK`.

    Raises
    ------
    DeviceError
        A device that is missing here, saying why (``cuda``: without numba-cuda or without
        a GPU, saying which); or a value not in :data:`DEVICE_CHOICES`.
    """
    if device not in DEVICE_CHOICES:
        raise DeviceError(f"{parameter}: got {device!r}, expected one of {', '.join(DEVICE_CHOICES)}", parameter=parameter)
    if device != AUTO:
        why = DEVICES[device].missing()
        if why is not None:
            raise DeviceError(f"{parameter}: {device}, but {why}", parameter=parameter)
        return device
    passed = []
    for name in AUTO_PREFERS:
        why = DEVICES[name].missing()
        if why is None:
            return name
        passed.append(why)
    note(f"{parameter} is {AUTO}: labelling on {DEVICES[AUTO_FALLBACK].shown}, as {'; '.join(passed)}")
    return AUTO_FALLBACK
