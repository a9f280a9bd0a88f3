"""The documentation site builds with no warning (issue 39): ``mkdocs build --strict`` as CI runs it.

One build per test session (about 10 s on a quiet 2-core machine), then checks of what it made: a page
of the API reference for every module of ``src/handeye`` (found here by walking the package, as
``docs/gen_pages.py`` does, so a module without a page fails), the link specification included once,
and the figures table rendered. Skips, saying why, when the docs tools (the ``docs`` extra) are absent.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
TOOLS = ("mkdocs", "material", "mkdocstrings", "mkdocstrings_handlers.python", "mkdocs_gen_files", "mkdocs_literate_nav")
MISSING = [name for name in TOOLS if importlib.util.find_spec(name.split(".")[0]) is None
           or importlib.util.find_spec(name) is None]
pytestmark = pytest.mark.skipif(bool(MISSING), reason=f"the docs tools are not installed ({', '.join(MISSING)}): "
                                                      'pip install -e ".[docs]"')


def build(config: Path, site: Path) -> tuple[int, list[str]]:
    """Run ``mkdocs build --strict`` on ``config`` into ``site``; its exit status and its warning lines."""
    env = {**os.environ, "DISABLE_MKDOCS_2_WARNING": "true", "NO_MKDOCS_2_WARNING": "1", "NO_COLOR": "1"}
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file", str(config),
                           "--site-dir", str(site)], cwd=config.parent, env=env, capture_output=True, text=True,
                          timeout=600)
    output = done.stdout + done.stderr
    warnings = [line for line in output.splitlines() if re.match(r"\s*(\x1b\[[\d;]*m)*(WARNING|ERROR)\b", line)]
    return done.returncode, warnings


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    status, warnings = build(REPO / "mkdocs.yml", out)
    assert status == 0 and not warnings, "mkdocs build --strict: " + "\n".join(warnings or ["failed"])
    return out


def test_the_site_builds_with_no_warning(site):
    assert (site / "index.html").is_file()


def test_the_warning_check_sees_a_broken_link(tmp_path):
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "index.md").write_text("# x\n\n[gone](nowhere.md)\n", encoding="utf-8")
    (tmp_path / "mkdocs.yml").write_text("site_name: x\n", encoding="utf-8")
    status, warnings = build(tmp_path / "mkdocs.yml", tmp_path / "site")
    assert status != 0 and any("nowhere.md" in line for line in warnings), warnings


def _modules() -> list[tuple[str, ...]]:
    package = REPO / "src" / "handeye"
    found = []
    for path in package.rglob("*.py"):
        parts = path.relative_to(package.parent).with_suffix("").parts
        parts = parts[:-1] if parts[-1] == "__init__" else parts
        in_packages = all((package.parent.joinpath(*parts[:i]) / "__init__.py").exists() for i in range(1, len(parts)))
        if in_packages and not any(part.startswith("_") for part in parts):
            found.append(parts)
    return found


def test_every_module_has_its_api_page_with_its_docstring(site):
    modules = _modules()
    assert len(modules) > 100, len(modules)
    missing = [".".join(parts) for parts in modules if not (site / "reference" / Path(*parts) / "index.html").is_file()]
    assert not missing, missing
    page = (site / "reference" / "handeye" / "calibration" / "absolute_orientation" / "index.html").read_text(encoding="utf-8")
    assert "Horn" in page and "rotation_between_vectors" in page
    roles = [path for path in (site / "reference").rglob("index.html")
             if re.search(r":(class|func|meth|data|mod|attr):<code>", path.read_text(encoding="utf-8"))]
    assert not roles, f"Sphinx roles shown literally (docs/hooks.py): {roles[:3]}"


def test_the_link_specification_is_included_once(site):
    protocol = (REPO / "src" / "handeye" / "rapid" / "PROTOCOL.md").read_text(encoding="utf-8")
    headings = [line.lstrip("#").strip() for line in protocol.splitlines() if line.startswith("## ")]
    page = (site / "controller-links" / "index.html").read_text(encoding="utf-8")
    for heading in headings[:3]:
        assert re.sub(r"[`*]", "", heading).split(" (")[0] in page, heading
    copies = [path for path in site.rglob("index.html") if "HeSocket" in path.read_text(encoding="utf-8")
              and "Link recovery" in path.read_text(encoding="utf-8")]
    assert [path.parent.name for path in copies] == ["controller-links"], copies


def test_the_figures_page_renders_its_table_and_links_the_benchmarks_notes(site):
    page = (site / "figures" / "index.html").read_text(encoding="utf-8")
    assert page.count("<tr>") >= 25
    assert 'href="../benchmarks/core/"' in page and (site / "benchmarks" / "core" / "index.html").is_file()
