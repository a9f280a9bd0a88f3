"""What a newcomer reads first: the README, the documentation pages and the help texts say one thing,
and only what is true.

Each test stands for a finding of a newcomer's review: three different demo times, links outside a
user's clone, help texts that named a 1 m limit (it is 500 mm) or left out a protocol, a 700-line
README (issue 39: it is a front page now, the manual is ``docs/``).
"""

import re
from pathlib import Path

import pytest

from handeye.station.cli import build_parser
from handeye.station.report.quality import QualityThresholds

REPO = Path(__file__).resolve().parents[1]
README = (REPO / "README.md").read_text(encoding="utf-8")
DOCS = REPO / "docs"
PAGES = {path.name: path.read_text(encoding="utf-8") for path in sorted(DOCS.glob("*.md"))}
FIGURES = PAGES["figures.md"]
#: The two set-up commands, character for character (the README's and the getting-started page's).
SETUP_COMMANDS = (
    "python3 -m venv .venv && . .venv/bin/activate && pip install -e . && handeye demo",
    'python3 -m venv .venv && . .venv/bin/activate && pip install -q -e ".[test]" && python -m pytest -q -n auto',
)
SHARED_CONVENTIONS = REPO.parent / "shared" / "conventions.md"
STATION_PAGE = (REPO / "docs" / "station.md").read_text(encoding="utf-8")


def _help(*words: str) -> str:
    parser = build_parser()
    for word in words:
        parser = next(a for a in parser._actions if a.dest in ("command", "mock_target")  # noqa: SLF001
                      or getattr(a, "choices", None) and word in (a.choices or {})).choices[word]
    return parser.format_help()


def _links(text: str) -> list[str]:
    return re.findall(r"\]\(([^)]+)\)", text) + re.findall(r"`(\.\./[^`]+)`", text)


def test_the_readme_links_nothing_outside_a_users_clone():
    links = _links(README)
    outside = [link for link in links if link.startswith("../")]
    assert not outside, outside
    for link in links:
        if not link.startswith(("http", "#")):
            assert (REPO / link.split("#")[0]).exists(), link


def test_the_docs_pages_link_only_pages_and_files_of_the_clone():
    # A page's link is to another page (docs/) or to a file of the repository, which the site publishes
    # at its repository path (docs/gen_pages.py): benchmarks/core/README.md from figures.md.
    for name, text in PAGES.items():
        for link in _links(text):
            if link.startswith(("http", "#")):
                continue
            target = link.split("#")[0]
            assert not target.startswith("../"), (name, link)
            if target.startswith("reference/"):  # the API reference: a page per module, made at build time
                module = REPO / "src" / Path(target).relative_to("reference").with_suffix("")
                module = module.parent if module.name == "index" else module
                assert (module / "__init__.py").exists() or module.with_suffix(".py").exists(), (name, link)
                continue
            assert (DOCS / target).exists() or (REPO / target).exists(), (name, link)


def test_the_conventions_the_readme_points_to_are_in_the_repository():
    assert "(CONVENTIONS.md)" in README
    if not SHARED_CONVENTIONS.exists():
        pytest.skip("../shared/conventions.md is only beside a development checkout")
    assert (REPO / "CONVENTIONS.md").read_text(encoding="utf-8") == SHARED_CONVENTIONS.read_text(encoding="utf-8")


def test_the_demo_time_is_stated_once_and_the_same_everywhere():
    from handeye.station.commands import demo

    everything = README + "".join(PAGES.values())
    stated = {
        "set-up": re.findall(r"station on the embedded mock robot and camera \(about (\d+) s\)", everything),
        "figures": re.findall(r"read-back identical, (\d+) s on a quiet machine \| `handeye demo`", everything),
        "demo --help": re.findall(r"What happens \(about (\d+) s", demo.EPILOG),
    }
    assert all(len(found) == 1 for found in stated.values()), stated
    assert re.search(r"station on the embedded mock robot and camera \(about \d+ s\)", README)
    assert re.search(r"read-back identical, \d+ s on a quiet machine \| `handeye demo`", FIGURES)
    assert len({found[0] for found in stated.values()}) == 1, f"the demo's time is given as {stated}"
    assert "half a minute" not in demo.EPILOG + everything


def test_the_setup_section_says_where_the_output_goes_what_pass_means_and_what_next():
    setup = README.split("## Set-up", 1)[1].split("\n## ", 1)[0]
    for words in ("PASS", "handeye_demo", "next"):
        assert words in setup, words


def test_the_readme_is_a_front_page_with_the_two_setup_commands_and_the_reports_picture():
    assert len(README.splitlines()) <= 150, "the README is the front page; the manual is docs/"
    for command in SETUP_COMMANDS:
        assert f"```sh\n{command}\n```" in README, command
        assert f"```sh\n{command}\n```" in PAGES["getting-started.md"], command
    picture = re.search(r"!\[[^\]]*\]\((docs/[^)]+\.png)\)", README)
    assert picture and (REPO / picture.group(1)).stat().st_size > 10_000, "the README shows the report"


def _figure_rows() -> list[list[str]]:
    table = FIGURES.split("| what | target | measured | command |\n|---|---|---|---|\n", 1)
    assert len(table) == 2, "the figures page keeps the README's table format"
    rows = []
    for line in table[1].splitlines():
        if not line.startswith("|"):
            break
        rows.append([cell.strip() for cell in line.strip("|").split(" | ")])
    return rows


def test_every_figure_has_its_command_and_the_scripts_it_names_exist():
    rows = _figure_rows()
    assert len(rows) >= 25, len(rows)
    for row in rows:
        assert len(row) == 4 and all(row), row
        command = row[3]
        assert command.startswith(("same", "`")), row
        for script in re.findall(r"python ((?:benchmarks|docs)/\S+?\.py)\b", command):
            assert (REPO / script).is_file(), script
        for note in re.findall(r"\]\(([^)]+)\)", command):
            assert (REPO / note).is_file(), note


def test_writeback_help_states_the_camera_offset_limits_it_applies():
    text = " ".join(_help("writeback").split())
    limits = QualityThresholds()
    assert f"{limits.min_camera_offset_mm:g}-{limits.max_camera_offset_mm:g} mm from the flange" in text
    assert not re.search(r"(?<![\d.])1 m\b", text)


def test_mock_help_names_every_protocol_a_mock_serves():
    from handeye.mocks.backends import mock_protocols

    for text in (_help("mock"), _help("mock", "controller")):
        for name in mock_protocols():
            assert name in text, (name, text)


def test_mock_help_says_the_rws_certificate_is_new_at_every_start():
    assert "new at every start" in " ".join(_help("mock", "controller").split())


def test_every_repository_path_the_readme_and_the_pages_name_exists():
    # A module or file that moves (issue 39's new rooms) must take the pages that name it along.
    named = set()
    for text in (README, *PAGES.values()):
        named |= {path.rstrip(".,:;") for path in re.findall(r"(?:src/handeye|benchmarks|tests)/[\w./*-]+", text)}
    assert len(named) > 50, len(named)
    missing = [path for path in sorted(named) if not (list(REPO.glob(path)) if "*" in path else (REPO / path).exists())]
    assert not missing, f"named in the README or docs/ but not in the repository: {missing}"


def _conventions_text() -> str:
    if not SHARED_CONVENTIONS.exists():
        pytest.skip("../shared/conventions.md is only beside a development checkout")
    return SHARED_CONVENTIONS.read_text(encoding="utf-8")


def test_every_command_is_in_the_conventions_or_an_extension_the_readme_lists():
    # issue 42 (f): `handeye plugins` (and verify, import, cell, stereo) exist beyond CONVENTIONS.md's
    # list; they are allowed only as extensions the README names as such and lists in its table
    from handeye.station.cli import command_names

    fixed = set(re.findall(r"`handeye ([a-z]+)", _conventions_text()))
    commands = set(command_names())
    assert fixed <= commands, f"CONVENTIONS.md fixes commands the CLI lacks: {sorted(fixed - commands)}"
    sentence = re.search(r"CONVENTIONS\.md fixes the\s+names of (.+?); (.+?) are this package's\s+extensions",
                         STATION_PAGE, re.S)
    assert sentence, "docs/station.md does not say which commands are extensions beyond CONVENTIONS.md"
    said_fixed, said_extra = (set(re.findall(r"`([a-z]+)`", part)) for part in sentence.groups())
    assert said_fixed == fixed, (said_fixed, fixed)
    assert said_extra == commands - fixed, (said_extra, commands - fixed)
    table = set(re.findall(r"^\| `([a-z]+)[ `]", STATION_PAGE, re.M))
    assert commands - fixed <= table, f"extensions missing from the commands table: {sorted(commands - fixed - table)}"
