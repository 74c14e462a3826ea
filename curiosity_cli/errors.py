"""Exception types the library raises for a user's mistake.

The CLI turns every :class:`CuriosityError` into a one-line ``Error: …`` message and exit
code 1; anything else is a bug and keeps its traceback.

Library messages name the library's own arguments, never command-line options: the
command line knows which option gave an argument, and says so (:meth:`CuriosityError.render`).
"""


def unwinding_interrupt(error: BaseException) -> bool:
    """Whether ``error`` was raised while a KeyboardInterrupt (Ctrl-C or SIGTERM) unwound the command.

    A library's clean-up can raise its own error as the interrupt passes through it
    (``np.savez_compressed`` closing a half-opened zip member raises ValueError), and
    that error, not the interrupt, is what comes up; it is the interrupt's echo, not a
    fault to report. Numba's dispatcher, interrupted in a kernel call, raises SystemError
    from the interrupt.
    """
    seen = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return False


#: Where a message says which stage to run (again), with its ``force`` argument or without.
RERUN = "{rerun}"


class CuriosityError(Exception):
    """A problem with the user's input that one line can explain.

    Parameters
    ----------
    message : str
        The line. With ``parameter``, it begins with that argument's name; with
        ``rerun``, it holds :data:`RERUN` where the remedy goes.
    parameter : str, optional
        The argument at fault, e.g. ``"out"`` for ``out: expected a .png file name``.
    rerun : str, optional
        The stage (``"extract"``, ``"explore"``, ``"label"``) that makes the files at
        fault anew.
    force : bool
        Whether the stage needs its ``force`` argument for that (files it would take as
        current), or makes them anyway (files missing, or broken, which it redoes).
    """

    def __init__(
        self, message: str, *, parameter: str | None = None, rerun: str | None = None, force: bool = True,
    ):
        if parameter is not None and not message.startswith(parameter):
            raise ValueError(f"the message must begin with {parameter!r}: {message!r}")
        super().__init__(message)
        self.parameter = parameter
        self.rerun = rerun
        self.force = force

    def render(self, option: str | None = None, rerun: str | None = None) -> str:
        """The message with ``option`` for the parameter's name and ``rerun`` for the remedy.

        Without them, the library's own words: the parameter's name, and e.g.
        ``explore with force=True`` (or ``explore``, without ``force``).
        """
        message = str(self.args[0]) if self.args else ""
        if self.parameter is not None and option is not None:
            message = option + message[len(self.parameter):]
        if self.rerun is not None:
            own = f"{self.rerun} with force=True" if self.force else self.rerun
            message = message.replace(RERUN, rerun if rerun is not None else own)
        return message

    def __str__(self) -> str:
        return self.render()


class ConfigError(CuriosityError):
    """A YAML config (or an override of one of its keys) that does not validate."""


class DatasetError(CuriosityError):
    """A dataset whose image, labels or legend cannot be used."""


class ParameterError(CuriosityError, ValueError):
    """A function argument out of its range: a user's mistake at the CLI, a ValueError to code."""


class UsageError(ParameterError):
    """Arguments that do not go together, or a value in a form its argument does not take.

    The command line reports it as a usage error (exit code 2) on the option that gave
    ``parameter``. The message begins ``parameter: ``; it may name other arguments in
    backquotes (`` `backend` ``), which the command line writes as their options.
    """

    def __init__(self, message: str, *, parameter: str):
        if not message.startswith(f"{parameter}: "):
            raise ValueError(f"the message must begin with {parameter + ': '!r}: {message!r}")
        super().__init__(message, parameter=parameter)

    def detail(self, options: dict[str, str]) -> str:
        """The message after ``parameter: ``, each `` `name` `` written ``options[name]`` where it has one."""
        return with_options(self.render()[len(self.parameter) + 2 :], options)


def with_options(text: str, options: dict[str, str]) -> str:
    """``text`` with each argument it names in backquotes (`` `name` ``) written ``options[name]`` where it has one:
    a library message in a front end's words."""
    import re

    return re.sub(r"`([a-z_]+)`", lambda m: options.get(m.group(1), m.group(0)), text)
