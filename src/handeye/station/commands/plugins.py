"""``handeye plugins``: every installed plug-in, by group, with what it can do (and, for one that does
not load, why)."""

from __future__ import annotations

import argparse

from .argtypes import Subcommands

HELP = "list the installed plug-ins (methods, controller protocols, camera back ends) and what each can do"

EPILOG = """\
Other installed packages add methods, controller protocols and camera back ends through the
entry-point groups handeye.methods, handeye.controllers and handeye.cameras (docs/extending.md).
For each one this lists its package, what it is, and for each command that takes one of its kind
whether it serves it or what it lacks (a protocol without a mock is no choice of demo --protocol).

Each plug-in is imported to know, under the time bound HANDEYE_PLUGIN_TIME_S (default 30 s): one
whose import fails is listed with the error, one that hangs with "did not load within N s". Other
commands import only the plug-ins they use.

Examples:
  handeye plugins
  handeye plugins --json -      # {"methods": [...], "controllers": [...], "cameras": [...]}, one object
                                # per plug-in: name, provider, what, unusable, serves, lacks
"""


def add_parser(sub: Subcommands) -> argparse.ArgumentParser:
    p = sub.add_parser("plugins", help=HELP, description=HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", metavar="FILE", help="write the list as JSON ('-' = stdout)")
    return p


def run(args: argparse.Namespace) -> int:
    from ...base import plugin_time_s
    from ..output import check_output_file, write_json
    from ..plugins import installed_plugins, plugin_lines

    if args.json and args.json != "-":
        check_output_file(args.json)
    if args.json != "-":
        print(f"loading each installed plug-in (at most {plugin_time_s():g} s each) ...", flush=True)
    groups = installed_plugins()
    if args.json:
        write_json(args.json, {group.key: [row.to_dict() for row in rows] for group, rows in groups})
    if args.json != "-":
        print("\n".join(plugin_lines(groups)))
    return 0
