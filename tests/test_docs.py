"""The documentation that lives in the repository: README.md and docs/*.md.

Three regression locks:

* every relative link in README.md and docs/*.md points to a file that exists and,
  where it names an anchor (``file.md#heading`` or ``#heading``), to a heading of
  that Markdown file (anchors as GitHub makes them: lower case, punctuation but
  ``-`` and ``_`` dropped, spaces to ``-``, ``-1``, ``-2`` ... for repeated headings);
* every dotted name of the project's code in backticks there
  (``harness.compare.regions.scene_caustic_region``, ``renderers.mitsuba.llvm``,
  ``python -m harness.system``) resolves: the longest prefix that is a module
  imports, and the rest are attributes of it;
* no file of the product (the packages, the tests, the docs, the README and the
  build files) points the reader outside the repository for an explanation: no
  citation of the team's design guide by file name and no issue number. Facts are
  stated where they are used, or the repository's own docs are named.
"""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCS = sorted((REPO / "docs").glob("*.md"))
MARKDOWN = [REPO / "README.md", *DOCS]

#: The project's top-level packages: the folders beside this one with an __init__.py.
PACKAGES = sorted(p.parent.name for p in REPO.glob("*/__init__.py"))
#: A dotted name rooted at one of them, not part of a path or a longer word.
DOTTED = re.compile(rf"(?<![\w./-])((?:{'|'.join(PACKAGES)})(?:\.[A-Za-z_]\w*)+)")
#: Inline Markdown links [text](target); images too (a leading "!" changes nothing).
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
#: Citations that point outside the repository. The design guide's file name and the
#: word of an issue are assembled, so that this file does not match its own pattern.
ISSUE = "iss" + "ue"
GUIDE_FILE = "DES" + "IGN.md"
CITATION = re.compile(
    rf"{re.escape(GUIDE_FILE)}"
    r"|\b[Ii]ssues?\s+#?\d+"              # a number: "<issue> 15", "<issue> #3"
    r"|\b[Ii]ssue\s+\"|\(issue\b"         # the issue "Title", (issue ...)
    r"|\bthe\s+issue(?:'s)?\b",           # the issue asks, the issue's bound
)
#: Where a citation may not appear: product code, tests, docs and build files.
CITED_ROOTS = ("harness", "renderers", "reports", "scenes", "tests", "docs", ".ci")
CITED_FILES = ("README.md", "tox.ini", "pyproject.toml")
TEXT_SUFFIXES = {".py", ".glsl", ".toml", ".md", ".ini", ".js", ".mjs", ".css", ".html",
                 ".j2", ".txt", ".json", ".csv", ".cfg", ".sh", ""}
#: Folders of installed third-party files (npm's), not the product's own.
INSTALLED = {"__pycache__", "node_modules"}


def _outside_fences(text: str) -> list[str]:
    """The lines of ``text`` outside fenced code blocks."""
    lines, fenced = [], False
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if not fenced:
            lines.append(line)
    return lines


def _slug(heading: str) -> str:
    """GitHub's anchor of a heading's text."""
    text = heading.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every anchor GitHub generates for the headings of the Markdown file ``path``."""
    seen: dict[str, int] = {}
    result = set()
    for line in _outside_fences(path.read_text(encoding="utf-8")):
        match = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not match:
            continue
        slug = _slug(match.group(1))
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        result.add(slug if count == 0 else f"{slug}-{count}")
    return result


def relative_links(path: Path) -> list[str]:
    """The link targets in ``path`` that are not URLs (inline code spans left out)."""
    targets = []
    for line in _outside_fences(path.read_text(encoding="utf-8")):
        for target in LINK.findall(re.sub(r"`[^`]*`", "", line)):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target):   # http:, https:, mailto:
                continue
            targets.append(target)
    return targets


def test_slug_follows_github():
    """Regression lock of the anchor rule on headings of these docs (GitHub drops
    backticks, colons and apostrophes and keeps hyphens)."""
    assert _slug("What `compare` writes per scene") == "what-compare-writes-per-scene"
    assert _slug("The paper's claims: verdicts and their bootstrap") == \
        "the-papers-claims-verdicts-and-their-bootstrap"
    assert _slug("Presets: `paper` and `strong`") == "presets-paper-and-strong"


def dotted_names(path: Path) -> list[tuple[int, str]]:
    """(line, name) of every dotted name of the project inside a code span of the
    Markdown file ``path`` (fenced blocks left out)."""
    names, fenced = [], False
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if fenced:
            continue
        for span in re.findall(r"`([^`]+)`", line):
            names += [(number, name) for name in DOTTED.findall(span)]
    return names


def resolve(name: str) -> object:
    """The object ``name`` names: the longest prefix that is a module, imported, then
    each further part as an attribute. Raises ImportError or AttributeError."""
    parts = name.split(".")
    for end in range(len(parts), 0, -1):
        module = ".".join(parts[:end])
        try:
            found = importlib.import_module(module)
        except ModuleNotFoundError as error:
            if error.name is not None and module.startswith(error.name):
                continue  # not a module: try a shorter prefix
            raise  # the module exists and failed to import something of its own
        for part in parts[end:]:
            found = getattr(found, part)
        return found
    raise ImportError(f"no module in {name}")


@pytest.mark.parametrize("page", MARKDOWN, ids=lambda p: str(p.relative_to(REPO)))
def test_dotted_names_resolve(page):
    """Every ``package.module.name`` of the project in the page exists in the code."""
    broken = []
    for number, name in dotted_names(page):
        try:
            resolve(name)
        except (ImportError, AttributeError) as error:
            broken.append(f"{page.name}:{number}: `{name}` ({type(error).__name__}: {error})")
    assert not broken, "names that do not resolve:\n" + "\n".join(broken)


def test_a_broken_dotted_name_is_caught(tmp_path):
    """The name check can fail: a missing attribute and a missing module are both
    seen; paths, file names and fenced code are not names."""
    page = tmp_path / "page.md"
    page.write_text("`harness.compare.regions.scene_caustic_region` `renderers.mitsuba.llvm` "
                    "`harness.compare.regions.no_such_function` `reports.no_such_module.x` "
                    "`python -m harness.system` `tests/harness/test_cli.py` `metrics.json`\n"
                    "```\nharness.fenced.name\n```\n", encoding="utf-8")
    names = [name for _, name in dotted_names(page)]
    assert names == ["harness.compare.regions.scene_caustic_region",
                     "renderers.mitsuba.llvm", "harness.compare.regions.no_such_function",
                     "reports.no_such_module.x", "harness.system"]
    assert callable(resolve(names[0])) and resolve(names[1]).__name__ == names[1]
    with pytest.raises(AttributeError):
        resolve(names[2])
    with pytest.raises(AttributeError):
        resolve(names[3])


@pytest.mark.parametrize("page", MARKDOWN, ids=lambda p: str(p.relative_to(REPO)))
def test_relative_links_resolve(page):
    """Every relative link names an existing file and, if it has one, an existing
    anchor of that file."""
    broken = []
    for target in relative_links(page):
        file_part, _, anchor = target.partition("#")
        destination = (page.parent / file_part).resolve() if file_part else page
        if not destination.exists():
            broken.append(f"{target}: no such file")
            continue
        if anchor and destination.suffix == ".md" and anchor not in anchors(destination):
            broken.append(f"{target}: no heading with anchor #{anchor}")
    assert not broken, f"{page.name}: " + "; ".join(broken)


def test_a_broken_link_is_caught(tmp_path):
    """The link check can fail: a missing file and a missing anchor are both seen."""
    page = tmp_path / "page.md"
    page.write_text("# Title\n\n[a](#title) [b](#nothing) [c](missing.md) "
                    "`[d](#code-span)`\n```\n[e](#fenced)\n```\n", encoding="utf-8")
    assert relative_links(page) == ["#title", "#nothing", "missing.md"]
    assert anchors(page) == {"title"}


def _cited_files():
    for root in CITED_ROOTS:
        for path in sorted((REPO / root).rglob("*")):
            if path.is_file() and not INSTALLED & set(path.parts) \
                    and path.suffix in TEXT_SUFFIXES and path != Path(__file__).resolve():
                yield path
    for name in CITED_FILES:
        yield REPO / name


def test_nothing_cites_outside_the_repository():
    """No comment, docstring, data file or page names the design guide by file name
    or an issue: each states its fact or names the repository's own docs."""
    hits = []
    for path in _cited_files():
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        for number, line in enumerate(text.splitlines(), 1):
            if CITATION.search(line):
                hits.append(f"{path.relative_to(REPO)}:{number}: {line.strip()}")
    assert not hits, "citations outside the repository:\n" + "\n".join(hits)


def test_the_citation_check_can_fail():
    """The pattern catches each form a citation took."""
    for line in (f"see {GUIDE_FILE}, radiometric contract", f"the bound of {ISSUE} 15",
                 f"({ISSUE} 17, part 4)", f'the {ISSUE} "Every failure is one clear line"',
                 f"the {ISSUE}'s bound", f"{ISSUE.title()} 11, glass_sphere"):
        assert CITATION.search(line), line
    assert not CITATION.search("docs/reference.md, Noise and seeds")
