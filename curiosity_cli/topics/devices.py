"""Which device labels: ``label.device`` (``cpu``, ``cuda`` or ``auto``) made a device the chains can run on.

:class:`~curiosity_cli.topics.chains.FrozenChains` runs on ``"cpu"`` or ``"cuda"`` with
the same bytes (``topics/chains.py``). ``cuda`` needs numba-cuda (the optional extra
``curiosity[cuda]``) and a CUDA GPU that numba sees; ``auto`` takes the GPU when both are
there and the CPU otherwise, and says so once.
"""

from __future__ import annotations

from curiosity_cli.config import LABEL_DEVICES as DEVICE_CHOICES
from curiosity_cli.errors import CuriosityError
from curiosity_cli.files import note
#: How a user gets numba-cuda.
CUDA_EXTRA = "pip install 'curiosity[cuda]' (from a checkout: pip install -e '.[cuda]')"


class DeviceError(CuriosityError):
    """A device was asked for that this machine cannot label on."""


def cuda_missing() -> str | None:
    """Why labelling cannot run on a CUDA GPU here, in words; None when it can."""
    from curiosity_cli._numba import import_cuda

    try:
        import_cuda()
    except ImportError as exc:
        return f"it needs numba-cuda, the extra curiosity[cuda], which is not installed ({exc}): {CUDA_EXTRA}"
    from curiosity_cli.topics._chain_kernels_cuda import gpu_available

    ready, why = gpu_available()
    return None if ready else f"no CUDA GPU was found ({why})"


def resolve_device(device: str, *, parameter: str = "label.device") -> str:
    """The device ``device`` asks for on this machine: ``"cpu"`` or ``"cuda"``.

    Parameters
    ----------
    device : {"cpu", "cuda", "auto"}
    parameter : str
        The setting's name, for the messages.

    Returns
    -------
    str
        ``"cpu"`` or ``"cuda"``; ``auto`` without a usable GPU notes once, on stderr, why
        it labels on the CPU.

    Raises
    ------
    DeviceError
        ``cuda`` without numba-cuda or without a GPU, saying which is missing; or a value
        not in :data:`DEVICE_CHOICES`.
    """
    if device not in DEVICE_CHOICES:
        raise DeviceError(f"{parameter}: got {device!r}, expected one of {', '.join(DEVICE_CHOICES)}", parameter=parameter)
    if device == "cpu":
        return "cpu"
    why = cuda_missing()
    if why is None:
        return "cuda"
    if device == "auto":
        note(f"{parameter} is auto: labelling on the CPU, as {why}")
        return "cpu"
    raise DeviceError(f"{parameter}: cuda, but {why}", parameter=parameter)
