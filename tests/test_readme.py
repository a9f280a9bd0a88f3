"""What a newcomer reads first: the README and the help texts say one thing, and only what is true.

Each test stands for a finding of a newcomer's review: three different demo times, links outside a
user's clone, help texts that named a 1 m limit (it is 500 mm) or left out a protocol.
"""

import re
from pathlib import Path

import pytest

from handeye.station.cli import build_parser
from handeye.station.report.quality import QualityThresholds

REPO = Path(__file__).resolve().parents[1]
README = (REPO / "README.md").read_text(encoding="utf-8")
SHARED_CONVENTIONS = REPO.parent / "shared" / "conventions.md"


def _help(*words: str) -> str:
    parser = build_parser()
    for word in words:
        parser = next(a for a in parser._actions if a.dest in ("command", "mock_target")  # noqa: SLF001
                      or getattr(a, "choices", None) and word in (a.choices or {})).choices[word]
    return parser.format_help()


def test_the_readme_links_nothing_outside_a_users_clone():
    links = re.findall(r"\]\(([^)]+)\)", README) + re.findall(r"`(\.\./[^`]+)`", README)
    outside = [link for link in links if link.startswith("../")]
    assert not outside, outside
    for link in links:
        if not link.startswith(("http", "#")):
            assert (REPO / link.split("#")[0]).exists(), link


def test_the_conventions_the_readme_points_to_are_in_the_repository():
    assert "(CONVENTIONS.md)" in README
    if not SHARED_CONVENTIONS.exists():
        pytest.skip("../shared/conventions.md is only beside a development checkout")
    assert (REPO / "CONVENTIONS.md").read_text(encoding="utf-8") == SHARED_CONVENTIONS.read_text(encoding="utf-8")


def test_the_demo_time_is_stated_once_and_the_same_everywhere():
    from handeye.station.commands import demo

    stated = {
        "set-up": re.findall(r"station on the embedded mock robot and camera \(about (\d+) s\)", README),
        "figures": re.findall(r"read-back identical, (\d+) s on a quiet machine \| `handeye demo`", README),
        "demo --help": re.findall(r"What happens \(about (\d+) s", demo.EPILOG),
    }
    assert all(len(found) == 1 for found in stated.values()), stated
    assert len({found[0] for found in stated.values()}) == 1, f"the demo's time is given as {stated}"
    assert "half a minute" not in demo.EPILOG + README


def test_the_setup_section_says_where_the_output_goes_what_pass_means_and_what_next():
    setup = README.split("## Set-up", 1)[1].split("\n## ", 1)[0]
    for words in ("PASS", "handeye_demo", "next"):
        assert words in setup, words


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
