"""The controller section of ``src/handeye/station/config/example_station.yaml``, written from the back ends' declarations.

The lines between :data:`BEGIN` and :data:`END` (``controller.protocol`` and every back end's own
link settings, each under its back end with its help, default and note) are rendered here from the
registry (:data:`handeye.drivers.controller.backends.CONTROLLERS`: the package's own back ends, those
registered in code), never edited by hand; the rest of the file is. A test holds the shipped file to
:func:`render_example`, so a back end or a link setting added without regenerating it fails with the
command that does::

    python -m handeye.station.config.example          # rewrite src/handeye/station/config/example_station.yaml
    python -m handeye.station.config.example --check  # exit 1 when it is out of date
"""

from __future__ import annotations

import sys
import textwrap

import yaml

from ..backend_help import link_module

__all__ = ["BEGIN", "END", "REGENERATE", "controller_lines", "render_example", "example_problem", "main"]

#: The command that rewrites the generated part.
REGENERATE = "python -m handeye.station.config.example"
BEGIN = f"  # --- generated from the controller back ends (src/handeye/drivers/controller/backends.py): {REGENERATE}"
END = "  # --- end of the generated part"
#: Where the comments start, and how wide a line may be.
_COMMENT_COLUMN, _WIDTH = 37, 118


def _value(value) -> str:
    """A YAML scalar as the file writes it (``null``, ``Default User``, ``"sio1:"``)."""
    if value is None:
        return "null"
    return yaml.safe_dump(value, default_flow_style=True, width=1000).strip().removesuffix("\n...").strip()


def _commented(head: str, comment: str) -> list[str]:
    """``head`` then ``# comment`` from :data:`_COMMENT_COLUMN`, wrapped onto ``#`` lines below it."""
    first = f"{head:<{_COMMENT_COLUMN - 1}} "
    pad = " " * max(len(first), _COMMENT_COLUMN)
    wrapped = textwrap.wrap(comment, _WIDTH - len(pad) - 2, break_on_hyphens=False, break_long_words=False)
    return [f"{first}# {wrapped[0]}".rstrip()] + [f"{pad}# {part}" for part in wrapped[1:]]


def _backend_lines(name: str, settings: dict, written: set) -> list[str]:
    """A back end's heading and the link settings it declares first."""
    from ...drivers import CONTROLLERS  # noqa: PLC0415

    backend = CONTROLLERS[name]
    link = link_module(name)
    port = f"default port {backend.default_port}" if backend.default_port is not None else "no TCP port"
    module = f"RAPID module {link.module}" if link is not None else "no RAPID module"
    own = [s for s in backend.link_settings if s.key not in written]
    heading = f"{name}: {backend.help}; {module}; {port}" + ("" if own else "; no settings of its own")
    lines = ["  # " + part for part in textwrap.wrap(heading, _WIDTH - 4, break_on_hyphens=False)]
    for setting in own:
        declared, names = settings[setting.key]
        text = (f"{', '.join(names)}: " if len(names) > 1 else "") + declared.help
        text += f" (REQUIRED for {name})" if declared.required else ""
        lines += _commented(f"  {setting.key}: {_value(declared.default)}", "; ".join(filter(None, (text, declared.note))))
        written.add(setting.key)
    return lines


def controller_lines(names=None) -> list[str]:
    """The generated part of the controller section, :data:`BEGIN` and :data:`END` included.

    Parameters
    ----------
    names : sequence of str, optional
        The back ends to describe, in order; default: those registered in code (the package's own).
    """
    from ...drivers import CONTROLLERS, DEFAULT_PROTOCOL, link_settings  # noqa: PLC0415
    from .station import MOCK  # noqa: PLC0415

    names = CONTROLLERS.names_in_code() if names is None else tuple(names)
    choices = " | ".join(names + (MOCK,))
    lines = [BEGIN] + _commented(
        f"  protocol: {DEFAULT_PROTOCOL}", f"REQUIRED: {choices} (each described below; {MOCK}: the embedded mock "
        f"station, with camera.backend: {MOCK}), or a protocol an installed plug-in registers")
    settings, written = link_settings(), set()
    for name in names:
        lines += _backend_lines(name, settings, written)
    return lines + [END]


def render_example(text: str, names=None) -> str:
    """``text`` (the example file) with its generated part rendered anew (:func:`controller_lines`).

    Raises
    ------
    ValueError
        The file has no :data:`BEGIN` ... :data:`END` part.
    """
    lines = text.split("\n")
    try:
        start, stop = lines.index(BEGIN), lines.index(END)
    except ValueError:
        raise ValueError(f"the example station file has no generated part (a line {BEGIN!r} ... {END!r})") from None
    return "\n".join(lines[:start] + controller_lines(names) + lines[stop + 1:])


def example_problem(path=None) -> str | None:
    """None when the example file's generated part is what the back ends declare; else one line saying
    to regenerate it."""
    from .station import EXAMPLE_FILE  # noqa: PLC0415

    path = EXAMPLE_FILE if path is None else path
    text = path.read_text(encoding="utf-8")
    if render_example(text) == text:
        return None
    return (f"{path} does not document the controller back ends as they are declared (a back end or a link "
            f"setting was added or changed): run {REGENERATE}")


def main(argv: list[str] | None = None) -> int:
    """Rewrite the example file's generated part (``--check``: only say whether it is out of date)."""
    from .station import EXAMPLE_FILE  # noqa: PLC0415

    argv = sys.argv[1:] if argv is None else list(argv)
    problem = example_problem()
    if "--check" in argv:
        print(problem or f"{EXAMPLE_FILE}: up to date", file=sys.stderr if problem else sys.stdout)
        return 1 if problem else 0
    if problem:
        EXAMPLE_FILE.write_text(render_example(EXAMPLE_FILE.read_text(encoding="utf-8")), encoding="utf-8")
        print(f"rewrote the controller back ends' part of {EXAMPLE_FILE}")
    else:
        print(f"{EXAMPLE_FILE}: up to date")
    return 0


if __name__ == "__main__":
    sys.exit(main())
