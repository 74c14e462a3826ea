"""Exception types the library raises for a user's mistake.

The CLI turns every :class:`CuriosityError` into a one-line ``Error: …`` message and exit
code 1; anything else is a bug and keeps its traceback.
"""


class CuriosityError(Exception):
    """A problem with the user's input that one line can explain."""


class ConfigError(CuriosityError):
    """A YAML config (or a ``--set`` override) that does not validate."""


class DatasetError(CuriosityError):
    """A dataset whose image, labels or legend cannot be used."""


class ParameterError(CuriosityError, ValueError):
    """A function argument out of its range: a user's mistake at the CLI, a ValueError to code."""
