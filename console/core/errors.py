"""Errors a user can fix. The CLI and the console print them as one line, never a traceback."""


class UserError(Exception):
    """Bad input (profile, file, argument): the message names what, where, and the fix."""


class UsageError(UserError):
    """A command line argparse refused (unknown option, bad number, missing argument):
    the message names the command, the option and what to give
    (``console.core.options.Parser``)."""


class ProfileError(UserError):
    """A profile that does not validate."""


class SafetyRefusal(UserError):
    """The safety gate refused a plan or a relay switch; the message says why."""


class TableBusy(SafetyRefusal):
    """Refused by the table's state, not by the input: another process holds its outputs
    (a participant's study run, a console opened with other output settings). The same
    command works once that one lets go; the CLI exits with ``EXIT_CODE``."""

    #: the exit status of a command the table refused because it is busy
    EXIT_CODE = 5


class EStopped(Exception):
    """Another process (`haptable estop`) e-stopped this command's outputs; it stopped."""

    #: the exit status of a command stopped this way
    EXIT_CODE = 4


class EStopLatched(UserError):
    """The table's e-stop is latched: nothing plays until an operator resets it (a
    command that would open its outputs refuses in one line). ``why``: the latch's
    reason alone, for a console to word the refusal with its own key."""

    EXIT_CODE = 4

    def __init__(self, message: str, why: str = "") -> None:
        super().__init__(message)
        self.why = why
