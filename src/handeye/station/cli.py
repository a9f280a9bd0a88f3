"""The ``handeye`` command: parses, delegates to a library function, reports errors in one line.

Each sub-command lives in ``station/commands/<name>.py`` with two functions: ``add_parser`` (builds
its argparse sub-parser, importing nothing heavy) and ``run`` (does the work, importing what it
needs). A new command is one new module and one line in ``COMMANDS``.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import os
import sys
import warnings

from ..base import HandEyeError, UsageError

#: Sub-commands in the order ``handeye --help`` lists them: a module name, or ``(command, module)``
#: when the command's name cannot be a module's (``import`` is a Python keyword).
COMMANDS = ("demo", "capture", "calibrate", "writeback", "verify", "simulate", ("import", "import_"), "triangulate", "benchmark", "robot",
            "rapid", "cell", "mock", "stereo", "plugins", "plant", "kinematics")

DESCRIPTION = """\
Hand-eye calibration of a stereo camera on an ABB robot flange (eye-in-hand) or beside the robot
(eye-to-hand), from posture capture to RAPID tooldata.

At the station:
  handeye capture --config station.yaml --session cal_01   # plan, move, measure (resumable)
  handeye calibrate cal_01 --report                        # camera pose, quality, HTML report
  handeye writeback cal_01 --config station.yaml           # into the robot's tooldata, read back
Try it without hardware:
  handeye demo                                             # the whole job on the mock station
Every command explains itself: handeye COMMAND --help
"""


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line (``handeye CMD: error: ...``), exit code 2.

    Usage errors found by the commands' own checks (flags that exclude each other, values out of range)
    are :class:`~handeye.base.errors.UsageError`: ``main`` exits 2 on them too."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def format_help(self) -> str:
        """The help; an ``epilog`` given as a callable is written now (one that lists plug-ins, and so loads
        them, is written only when the help is asked for)."""
        if callable(self.epilog):
            self.epilog = self.epilog()
        return super().format_help()


def command_names() -> tuple[str, ...]:
    """The sub-commands' names, in ``COMMANDS`` order."""
    return tuple(entry if isinstance(entry, str) else entry[0] for entry in COMMANDS)


def build_parser(only: str | None = None, words=()) -> argparse.ArgumentParser:
    """The ``handeye`` parser; with ``only`` (a command's name), that command's sub-parser is built whole
    and every other one is a name and its one-line help: the other commands' options (which may list
    plug-ins, and so load them) are not built for a command that does not need them. ``words``, the
    command line, goes to an ``add_parser(sub, words)`` that takes it: one that offers a plug-in's own
    flags loads only the plug-in the line names (``--protocol X``), every one for ``--help``."""
    parser = OneLineParser(
        prog="handeye", description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for entry in COMMANDS:
        command_name, name = (entry, entry) if isinstance(entry, str) else entry
        module = importlib.import_module(f"{__package__}.commands.{name}")
        if only is None or command_name == only:
            takes_words = "words" in inspect.signature(module.add_parser).parameters
            command = module.add_parser(sub, words=None if only is None else list(words)) if takes_words \
                else module.add_parser(sub)
        else:
            command = sub.add_parser(command_name, help=module.HELP)
        command.set_defaults(_module=module)
    return parser


def _command_of(argv) -> str | None:
    """The sub-command ``argv`` names first (``None``: none, or an option first: ``handeye --help``)."""
    words = list(sys.argv[1:] if argv is None else argv)
    return words[0] if words and words[0] in command_names() else None


def main(argv: list[str] | None = None) -> int:
    command = _command_of(argv)
    parser = build_parser(only=command, words=sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(argv)
    if getattr(args, "_module", None) is None:
        parser.print_help()
        return 2
    try:
        with warnings.catch_warnings():
            # numeric noise (0/0 in a degenerate data set) is not for the operator: what it leads to is
            # reported as one line below
            warnings.simplefilter("ignore", RuntimeWarning)
            return int(args._module.run(args) or 0)
    except UsageError as exc:  # a flag combination or value our own code refuses: a usage error, as argparse's
        print(f"handeye {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except HandEyeError as exc:
        print(f"handeye {args.command}: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"handeye {args.command}: interrupted; everything written so far is kept", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except OSError as exc:  # safety net: every reader and writer reports its own OSErrors as HandEyeError
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        print(f"handeye {args.command}: error: {(exc.strerror or str(exc) or type(exc).__name__).lower()}{where}",
              file=sys.stderr)
        return 1
    except Exception as exc:  # a fault in code (a plug-in's or ours): one line naming whose
        from .unexpected import DEBUG_VARIABLE, unexpected_error_line

        if os.environ.get(DEBUG_VARIABLE, "") not in ("", "0"):
            raise
        print(f"handeye {args.command}: error: {unexpected_error_line(exc, args.command)}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
