"""Pages made at build time (mkdocs-gen-files runs this from the repository root).

- ``reference/``: one page per module of ``src/handeye``, found by walking the package tree (never a
  hand-written list: a module that moves or appears gets its page on the next build), and the
  section's navigation (``reference/SUMMARY.md``, read by mkdocs-literate-nav).
- The repository's own Markdown (``CONVENTIONS.md``, the benchmarks' and the rooms' notes) published
  at its path in the repository, so that a link written from the repository root in a page
  (``benchmarks/core/README.md``) is a link inside the site, and indexed in ``benchmarks/SUMMARY.md`` and ``src/SUMMARY.md``.
  ``src/handeye/rapid/PROTOCOL.md`` is left out: the controller-links page includes it (one copy).
"""

from __future__ import annotations

from pathlib import Path

import mkdocs_gen_files

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "handeye"
#: Markdown of the repository that is not a page of its own: the front page, and what a page includes.
NOT_PUBLISHED = {"README.md", "src/handeye/rapid/PROTOCOL.md"}
#: Where the repository's notes are looked for (the docs, the environment and the tests are not notes).
NOTE_ROOTS = ("CONVENTIONS.md", "benchmarks", "src")


def module_names() -> list[tuple[str, ...]]:
    """Dotted parts of every public module and package under ``src/handeye``, sorted.

    Returns
    -------
    list of tuple of str
        ``("handeye", "calibration", "quaternion")`` for each module; a package is named by its
        folder. Names starting with ``_`` (private modules, ``__main__``) are left out.
    """
    names = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if any(part.startswith("_") for part in parts):
            continue
        if not all((PACKAGE.parent.joinpath(*parts[:i]) / "__init__.py").exists() for i in range(1, len(parts))):
            continue  # a script in a data folder, not a module
        names.append(parts)
    return names


def write_reference() -> None:
    """Write ``reference/<dotted/path>.md`` (a package's ``index.md``) with its ``:::`` directive for every module, and the nav."""
    nav = mkdocs_gen_files.Nav()
    for parts in module_names():
        is_package = (PACKAGE.parent.joinpath(*parts) / "__init__.py").exists()
        doc = Path(*parts, "index.md") if is_package else Path(*parts).with_suffix(".md")
        nav[parts] = doc.as_posix()
        with mkdocs_gen_files.open(Path("reference", doc), "w") as out:
            out.write(f"# `{'.'.join(parts)}`\n\n::: {'.'.join(parts)}\n")
    with mkdocs_gen_files.open("reference/SUMMARY.md", "w") as out:
        out.writelines(nav.build_literate_nav())


def repository_notes() -> list[Path]:
    """The repository's Markdown files published as pages, relative to the repository root."""
    found = []
    for root in NOTE_ROOTS:
        path = ROOT / root
        found += [path] if path.is_file() else sorted(path.rglob("*.md"))
    notes = [path.relative_to(ROOT) for path in found]
    return [note for note in notes if note.as_posix() not in NOT_PUBLISHED and "__pycache__" not in note.parts]


def title_of(text: str, fallback: str) -> str:
    """The first Markdown heading of ``text``, or ``fallback`` when it has none."""
    for line in text.splitlines():
        if line.startswith("#"):
            return line.lstrip("#").strip().replace("`", "")
    return fallback


def write_notes() -> None:
    """Publish each note at its repository path; ``benchmarks/`` and ``src/`` get a nav file each."""
    navs: dict[str, list[str]] = {}
    for note in repository_notes():
        text = (ROOT / note).read_text(encoding="utf-8")
        with mkdocs_gen_files.open(note.as_posix(), "w") as out:
            out.write(text)
        mkdocs_gen_files.set_edit_path(note.as_posix(), Path("..", note).as_posix())
        for picture in sorted((ROOT / note.parent).glob("*.png")) if len(note.parts) > 1 else ():
            with mkdocs_gen_files.open((note.parent / picture.name).as_posix(), "wb") as out:
                out.write(picture.read_bytes())  # a note's figures beside it, so its links hold
        if len(note.parts) > 1:
            inside = Path(*note.parts[1:]).as_posix()
            label = f"{note.parent.as_posix()}: {title_of(text, note.name)}"
            navs.setdefault(note.parts[0], []).append(f"* [{label}]({inside})\n")
    for folder, lines in navs.items():
        with mkdocs_gen_files.open(f"{folder}/SUMMARY.md", "w") as out:
            out.writelines(lines)


write_reference()
write_notes()
