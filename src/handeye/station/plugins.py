"""What the installed plug-ins are and what each can do: ``handeye plugins``.

Every entry point of handeye's groups (methods, controller protocols, camera back ends) is listed by
group, with its package, what it is and, for each command that takes an entry of its kind, whether it
serves that command or what it lacks. The commands' own checks decide (the same
:class:`~handeye.base.registry.Choices` the command line and the station config use), so the
list says what the commands will do. Each plug-in is loaded to know, under the time bound
(:mod:`handeye.base.time_bound`): one that fails or hangs is listed with why.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..base import Registry

__all__ = ["PluginGroup", "PluginRow", "plugin_groups", "installed_plugins", "plugin_lines"]


@dataclass(frozen=True)
class PluginGroup:
    """One kind of plug-in: its registry, its title, what one entry is, the commands that take one.

    Attributes
    ----------
    title : str
        ``methods``, ``controller protocols``, ``camera back ends``.
    registry : Registry
    uses : tuple of (str, callable)
        ``(the commands, choices())``: the commands an entry may serve and the
        :class:`~handeye.base.registry.Choices` they check a name against.
    what : callable
        ``what(entry) -> str``: one line on the loaded entry.
    """

    title: str
    registry: Registry
    uses: tuple
    what: Callable

    @property
    def key(self) -> str:
        """The group's JSON key: its entry-point group without ``handeye.`` (``methods``, ``controllers``)."""
        return self.registry.group.rpartition(".")[2]


@dataclass
class PluginRow:
    """One installed plug-in: ``name``, ``provider`` (its package and entry point), ``what`` it is (empty
    when it did not load), ``serves`` (``{commands: None when served, else what it lacks}``) and
    ``unusable`` (why it did not load, or None)."""

    name: str
    provider: str
    what: str = ""
    serves: dict = field(default_factory=dict)
    unusable: str | None = None

    def to_dict(self) -> dict:
        return {"name": self.name, "provider": self.provider, "what": self.what, "unusable": self.unusable,
                "serves": {use: why is None for use, why in self.serves.items()},
                "lacks": {use: why for use, why in self.serves.items() if why is not None}}


def _method_line(method) -> str:
    extra = "; only with a synthetic session's truth" if method.needs_truth else ""
    return f"{method.kind} method, {method.citation}{': ' + method.summary if method.summary else ''}{extra}"


def _controller_line(backend) -> str:
    keys = ", ".join(f"controller.{s.key}" for s in backend.link_settings)
    port = f"; default port {backend.default_port}" if backend.default_port else ""
    return f"{backend.help or 'controller link'}{port}{'; settings ' + keys if keys else ''}"


def _camera_line(backend) -> str:
    keys = ", ".join(f"camera.{s.key}" for s in backend.settings)
    return f"{backend.help or 'camera'}{' (simulated)' if backend.simulated else ''}{'; settings ' + keys if keys else ''}"


def plugin_groups() -> tuple[PluginGroup, ...]:
    """The kinds of plug-in, each with the commands that take one (imports the registries, no plug-in)."""
    from ..calibration import METHODS
    from ..drivers import CAMERAS
    from ..drivers import CONTROLLERS, rapid_protocol_choices
    from ..mocks import mock_protocol_choices
    from .config.station import camera_choices, protocol_choices

    return (
        PluginGroup("methods", METHODS, (
            ("calibrate --method, benchmark --methods", METHODS.choices),
            ("the report's method comparison (calibrate --report, demo)",
             lambda: METHODS.choices(lambda m: m.in_comparison, lacking="is not marked in_comparison")),
        ), _method_line),
        PluginGroup("controller protocols", CONTROLLERS, (
            ("controller.protocol of a station (capture, verify, writeback), robot", protocol_choices),
            ("demo --protocol, mock controller, mock.protocol", mock_protocol_choices),
            ("rapid generate", rapid_protocol_choices),
        ), _controller_line),
        PluginGroup("camera back ends", CAMERAS, (
            ("camera.backend of a station (capture, verify)", camera_choices),
        ), _camera_line),
    )


def installed_plugins() -> list[tuple[PluginGroup, list[PluginRow]]]:
    """Every installed plug-in, by group (each loaded under the time bound to know what it can do)."""
    from ..base import quiet_loads

    out = []
    with quiet_loads():  # the rows say why a plug-in did not load
        for group in plugin_groups():
            rows = []
            for name in group.registry.plugin_names():
                row = PluginRow(name, group.registry.provider(name) or "an installed package")
                entry = group.registry.get(name)
                if entry is None:
                    row.unusable = group.registry.unusable().get(name, "did not load")
                else:
                    row.what = group.what(entry)
                    for use, choices in group.uses:
                        options = choices()
                        row.serves[use] = None if name in options else (options.lacking or "cannot serve it")
                rows.append(row)
            out.append((group, rows))
    return out


def plugin_lines(groups: list[tuple[PluginGroup, list[PluginRow]]]) -> list[str]:
    """The text ``handeye plugins`` prints."""
    from ..base import unusable_clause

    lines = []
    for group, rows in groups:
        lines.append(f"{group.title} (entry-point group {group.registry.group}): "
                     f"{len(rows) or 'none'} installed")
        for row in rows:
            lines.append(f"  {row.name}: {row.provider}")
            if row.unusable is not None:
                lines.append(f"    {unusable_clause(row.unusable)}: fix or uninstall that package")
                continue
            lines.append(f"    {row.what}")
            lines += [f"    {use}: " + ("yes" if why is None else f"no, it {why}") for use, why in row.serves.items()]
        lines += [f"  {line}" for line in group.registry.ignored()]
    return lines
