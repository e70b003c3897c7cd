"""The ``haptable`` command. Sub-commands come from plugins (the core's included)."""

from __future__ import annotations

import argparse
import logging
import os
import sys
import warnings

from console.core.errors import EStopLatched, EStopped, TableBusy, UserError
from console.core.options import Parser, seconds_option
from console.files.profile_paths import find_profile
from console.runtime.context import Context

__all__ = ["Context", "build_parser", "main", "one_line", "seconds_option"]


def build_parser(plugins) -> argparse.ArgumentParser:
    parser = Parser(
        prog="haptable",
        description="HapTable operator console. Without a command: start the console.",
    )
    parser.add_argument(
        "--profile", "-p", help="profile name or .toml path (default: sim, or $HAPTABLE_PROFILE)"
    )
    parser.add_argument("--verbose", "-v", action="store_true")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, cmd in sorted(plugins.commands.items()):
        p = sub.add_parser(name, help=cmd.help, description=cmd.help)
        p.add_argument("--profile", "-p", dest="profile_sub", default=None, help=argparse.SUPPRESS)
        cmd.configure(p)
    return parser


def one_line(message: str) -> str:
    """An error message as one line: line breaks and other control characters (from
    a file's keys or values quoted in it) are escaped, a runaway message is cut."""
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in message)
    return text if len(text) <= 2000 else text[:2000] + " ..."


def first_line(message: str) -> str:
    """The first non-empty line of a message (a library's multi-line text cut to it)."""
    return next((ln.strip() for ln in message.splitlines() if ln.strip()), "")


def _log_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: object = None,
    line: str | None = None,
) -> None:
    """``warnings.showwarning`` while a command runs: a library's warning (numpy,
    scikit-learn ...) is one log line (shown with ``--verbose``), never its source line
    or an embedded traceback on the user's terminal."""
    text = one_line(first_line(str(message)))[:300]
    logging.getLogger("haptable.warnings").info("%s: %s", category.__name__, text)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    with warnings.catch_warnings():
        warnings.showwarning = _log_warning
        return _main(argv)


def _main(argv: list[str]) -> int:
    debug = os.environ.get("HAPTABLE_DEBUG") == "1"
    ctx = None
    try:
        # lazy: NumPy and plugins load after the arguments are read
        from console.cli import core_commands
        from console.config.plugins import load_plugins

        plugins = load_plugins(core=core_commands)
        parser = build_parser(plugins)
        args = parser.parse_args(argv)
        logging.basicConfig(
            level=logging.INFO if args.verbose else logging.WARNING, format="%(name)s: %(message)s"
        )
        command = args.command or "console"
        profile = getattr(args, "profile_sub", None) or args.profile
        if profile or os.environ.get("HAPTABLE_PROFILE"):  # named: found, or refused by
            # every command (none ignores it; estop and reset never come here: entry.py)
            find_profile(profile)
        ctx = Context(profile, plugins, argv)
        if command == "console" and args.command is None:
            args = parser.parse_args([*argv, "console"])
        code = int(plugins.commands[command].run(args, ctx) or 0)
        if ctx.estopped_by:  # it finished anyway: still say it was stopped
            raise EStopped(ctx.estopped_by)
        return code
    except EStopped as exc:
        return _estopped(str(exc))
    except TableBusy as exc:
        if ctx is not None and ctx.estopped_by:
            return _estopped(ctx.estopped_by)
        print(f"haptable: busy: {one_line(str(exc))}", file=sys.stderr)
        return TableBusy.EXIT_CODE
    except EStopLatched as exc:
        print(f"haptable: {one_line(str(exc))}", file=sys.stderr)
        return EStopLatched.EXIT_CODE
    except UserError as exc:
        if ctx is not None and ctx.estopped_by:  # what the e-stop made fail
            return _estopped(ctx.estopped_by)
        print(f"haptable: error: {one_line(str(exc))}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        if ctx is not None and ctx.estopped_by:
            return _estopped(ctx.estopped_by)
        print("haptable: interrupted (outputs silenced)", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except OSError as exc:
        if ctx is not None and ctx.estopped_by:
            return _estopped(ctx.estopped_by)
        if debug or not exc.filename:
            if debug:
                raise
            return _internal(exc)
        # a file or folder given to the command that cannot be read or written
        print(
            f"haptable: error: {one_line(str(exc.filename))}: {exc.strerror or exc}; "
            f"check the path and its permissions",
            file=sys.stderr,
        )
        return 2
    except Exception as exc:
        if ctx is not None and ctx.estopped_by:
            return _estopped(ctx.estopped_by)
        if debug:
            raise
        return _internal(exc)


def _internal(exc: BaseException) -> int:
    what = one_line(first_line(str(exc)))[:300]
    print(
        f"haptable: internal error: {type(exc).__name__}: {what} "
        f"(outputs silenced; HAPTABLE_DEBUG=1 shows the traceback; please report it)",
        file=sys.stderr,
    )
    return 3


def _estopped(reason: str) -> int:
    print(
        f"haptable: e-stopped by {reason}; the command stopped, its outputs closed", file=sys.stderr
    )
    return EStopped.EXIT_CODE


if __name__ == "__main__":
    sys.exit(main())
