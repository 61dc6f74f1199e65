"""The snippets of README.md and of the book (docs/book/src) run, and their links lead
somewhere: docs/book/src/contributing.md describes the conventions checked here.

Every fenced block has an info string. ```sh blocks run in bash (`set -e`, pipefail)
with the `dvrk-ident` of the tests ($DVRK_IDENT_BIN) first on PATH; ```python blocks run
in this interpreter, with the installed module. Both are written from the repository's
root and run in a fresh temporary copy of it (examples/, robots/, tests/fixtures/) with
../shared beside it, so a snippet can write files without touching the repository. A
block that reads ../shared skips visibly when it is absent, a Python block whose
imports are not installed likewise. ```rust blocks are doc tests of a crate that
includes their page (`#[doc = include_str!(...)]`); ```text, ```toml and ```json blocks
show text and are not run, nor is a block marked `norun` (```sh,norun) for commands
this test cannot run (installing, CI itself).
"""

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from conftest import REPO, SHARED

BOOK = REPO / "docs" / "book"
SRC = BOOK / "src"
# What a snippet may read from the repository, copied into its working folder.
COPIED = ("examples", "robots", "tests/fixtures")
RUN = {"sh", "python"}
# Shown, not run: cpp is the C library's example, compiled by its own tests; cmake a
# downstream project's lines, built by crates/dvrk-model-c/tests/installed/run.sh.
SHOWN = {"text", "toml", "json", "cpp", "cmake"}
# Pages the book includes ({{#include}}) whose blocks other tests run.
INCLUDED_ELSEWHERE = {
    "crates/dvrk-py/README.md": "tests/python/test_tutorial.py runs its Python tutorial; "
    "its install commands are those of .ci/wheel and .ci/run",
    "crates/dvrk-model-c/tests/cpp/readme.cpp": "crates/dvrk-model-c/tests/c_abi.rs "
    "(readme_cpp_example_runs) compiles and runs it",
}
# One snippet at most this long (s): a hang fails instead of stopping CI.
TIMEOUT = 600


def doc_pages():
    """README.md and the book's pages; none of them when the sources are absent (an
    installed module tested on its own)."""
    if not SRC.is_dir():
        return []
    return [REPO / "README.md", *sorted(SRC.glob("*.md"))]


@dataclass
class Block:
    page: Path
    line: int  # of the opening fence, 1-based
    lang: str
    attrs: tuple
    code: str

    @property
    def name(self):
        return f"{self.page.relative_to(REPO)}:{self.line}"


FENCE = re.compile(r"^( {0,3})(```+)(.*)$")


def fenced_blocks(page):
    """The fenced blocks of a Markdown page (``` fences, possibly indented in a list)."""
    blocks, current = [], None
    for number, line in enumerate(page.read_text().splitlines(), 1):
        m = FENCE.match(line)
        if current is None:
            if m:
                info = [w for w in re.split(r"[,\s]+", m.group(3).strip()) if w]
                current = dict(start=number, indent=len(m.group(1)), fence=m.group(2),
                               lang=info[0] if info else "", attrs=tuple(info[1:]), lines=[])
        elif m and m.group(2).startswith(current["fence"]) and not m.group(3).strip():
            blocks.append(Block(page, current["start"], current["lang"], current["attrs"],
                                "\n".join(current["lines"]) + "\n"))
            current = None
        else:
            current["lines"].append(line[current["indent"]:] if line[:current["indent"]].isspace()
                                    else line)
    assert current is None, f"{page}:{current['start']}: code block never closed"
    return blocks


def all_blocks():
    return [b for page in doc_pages() for b in fenced_blocks(page)]


def runnable(block):
    return block.lang in RUN and "norun" not in block.attrs


def doc_tested_pages():
    """The Markdown pages that a crate includes as documentation (so that `cargo test
    --doc` runs their Rust blocks), from the crates' sources."""
    pages = set()
    for rs in REPO.glob("crates/*/src/**/*.rs"):
        for m in re.finditer(r'#\[doc\s*=\s*include_str!\("([^"]+\.md)"\)\]', rs.read_text()):
            pages.add((rs.parent / m.group(1)).resolve())
    return pages


def test_every_block_is_run_or_marked():
    blocks = all_blocks()
    if not blocks:
        pytest.skip(f"SKIPPED: {SRC} not found (installed without the sources)")
    doc_tested = doc_tested_pages()
    problems = []
    for b in blocks:
        if b.lang in RUN or b.lang in SHOWN:
            continue
        if b.lang == "rust":
            if b.page.resolve() not in doc_tested:
                problems.append(f"{b.name}: a rust block in a page no crate runs as doc tests "
                                "(#[doc = include_str!(...)])")
        elif not b.lang:
            problems.append(f"{b.name}: a code block without an info string (sh, python, "
                            "rust, text, toml, json; ,norun for a command not to run)")
        else:
            problems.append(f"{b.name}: unknown info string {b.lang!r}")
    assert not problems, "\n".join(problems)
    assert sum(map(runnable, blocks)) >= 10, "the runner finds almost no snippet to run"


INCLUDE = re.compile(r"\{\{#include\s+([^}\s:]+)(?::([^}\s]*))?\s*\}\}")


def test_includes_are_known():
    """Every {{#include}} of the book is a part of README.md (whose blocks this file
    runs) or a page whose blocks another test runs."""
    pages = doc_pages()
    if not pages:
        pytest.skip(f"SKIPPED: {SRC} not found (installed without the sources)")
    for page in pages:
        for m in INCLUDE.finditer(page.read_text()):
            target = (page.parent / m.group(1)).resolve()
            assert target.exists(), f"{page}: {{{{#include {m.group(1)}}}}}: no such file"
            rel = target.relative_to(REPO).as_posix()
            assert rel == "README.md" or rel in INCLUDED_ELSEWHERE, (
                f"{page}: includes {rel}, whose blocks nothing runs: add it to "
                "INCLUDED_ELSEWHERE with the test that runs them, or run them here")
            if rel == "README.md" and m.group(2):
                text = target.read_text()
                assert f"ANCHOR: {m.group(2)}" in text, (
                    f"{page}: README.md has no anchor {m.group(2)!r}")
                # A relative link would resolve from the README in one place and from
                # the book's page in the other: the shared part has none.
                part = text.split(f"ANCHOR: {m.group(2)}", 1)[1].split("ANCHOR_END", 1)[0]
                links = [t for t in LINK.findall(part) if not re.match(r"[a-z][a-z0-9+.-]*:", t)]
                assert not links, f"README.md's part {m.group(2)!r}, in {page.name}, links {links}"


@pytest.fixture(scope="module")
def bin_dir(cli, tmp_path_factory):
    """A folder whose `dvrk-ident` is the binary under test, to put first on PATH."""
    d = tmp_path_factory.mktemp("bin")
    (d / "dvrk-ident").symlink_to(Path(cli).resolve())
    return d


def workspace(tmp_path):
    """A fresh copy of what the snippets read, laid out like the repository, with
    ../shared beside it (a link to the real one when present)."""
    root = tmp_path / "repo"
    for rel in COPIED:
        if (REPO / rel).exists():
            shutil.copytree(REPO / rel, root / rel, symlinks=False)
    root.mkdir(exist_ok=True)
    if SHARED.exists():
        (tmp_path / "shared").symlink_to(SHARED.resolve())
    return root


def needs_shared(block):
    if "../shared" in block.code and not SHARED.exists():
        pytest.skip(f"SKIPPED: {SHARED} not found (../shared absent): {block.name}")


def missing_imports(code):
    names = set(re.findall(r"^\s*import\s+([A-Za-z_]\w*)", code, re.M))
    names |= set(re.findall(r"^\s*from\s+([A-Za-z_]\w*)\S*\s+import", code, re.M))
    return sorted(n for n in names if importlib.util.find_spec(n) is None)


SNIPPETS = [b for b in all_blocks() if runnable(b)]


@pytest.mark.parametrize("block", SNIPPETS, ids=[b.name for b in SNIPPETS])
def test_snippet_runs(block, bin_dir, tmp_path):
    needs_shared(block)
    cwd = workspace(tmp_path)
    env = dict(os.environ)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    if block.lang == "sh":
        command = ["bash", "-e", "-o", "pipefail", "-c", block.code]
    else:
        missing = missing_imports(block.code)
        if missing:
            pytest.skip(f"SKIPPED: {block.name} imports {', '.join(missing)}, not installed")
        script = tmp_path / "snippet.py"
        script.write_text(block.code)
        command = [sys.executable, str(script)]
    r = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True,
                       timeout=TIMEOUT)
    assert r.returncode == 0, (
        f"{block.name} ({block.lang}) exited with {r.returncode}:\n{block.code}\n"
        f"--- stdout\n{r.stdout[-4000:]}\n--- stderr\n{r.stderr[-4000:]}")


# ------------------------------------------------------------------------------ links

LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)")


def slug(heading):
    """The anchor of a heading, as mdBook and the git hosts make it: lower case, Markdown
    code marks and punctuation dropped, spaces as hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading.strip().lower())
    return "".join("-" if c == " " else c for c in text if c.isalnum() or c in " -_")


def anchors(page):
    """The heading anchors of a page, those of the parts it includes too."""
    text = page.read_text()
    for m in INCLUDE.finditer(text):
        target = page.parent / m.group(1)
        part = target.read_text() if target.exists() else ""
        if m.group(2) and not m.group(2)[0].isdigit() and f"ANCHOR: {m.group(2)}" in part:
            part = part.split(f"ANCHOR: {m.group(2)}", 1)[1].split("ANCHOR_END", 1)[0]
        text += "\n" + part
    found, fence = set(), False
    for line in text.splitlines():
        if FENCE.match(line):
            fence = not fence
        elif not fence and re.match(r"#{1,6} ", line):
            found.add(slug(line.lstrip("#")))
    return found


def markdown_pages():
    skip = {"target", "node_modules"}
    return [p for p in sorted(REPO.rglob("*.md"))
            if not any(part in skip or part.startswith(".") for part in
                       p.relative_to(REPO).parts[:-1])]


def test_relative_links_lead_somewhere():
    """Every relative link of the repository's Markdown pages names a file that exists,
    and, into a Markdown page, a heading it has."""
    if not SRC.is_dir():
        pytest.skip(f"SKIPPED: {SRC} not found (installed without the sources)")
    broken = []
    for page in markdown_pages():
        text, fence = [], False
        for line in page.read_text().splitlines():
            if FENCE.match(line):
                fence = not fence
            elif not fence:
                text.append(re.sub(r"`[^`]*`", "", line))
        for target in LINK.findall("\n".join(text)):
            if re.match(r"[a-z][a-z0-9+.-]*:", target):
                continue  # https:, mailto:
            path, _, anchor = target.partition("#")
            dest = (page.parent / path).resolve() if path else page
            where = f"{page.relative_to(REPO)}: ({target})"
            if not dest.exists():
                broken.append(f"{where}: no such file")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                broken.append(f"{where}: no heading #{anchor} in {dest.name}")
    assert not broken, "\n".join(broken)


def test_every_chapter_is_in_the_summary():
    """mdBook only renders the pages SUMMARY.md lists (and create-missing is off, so a
    listed page that is missing fails the build): every page is listed."""
    if not SRC.is_dir():
        pytest.skip(f"SKIPPED: {SRC} not found (installed without the sources)")
    summary = (SRC / "SUMMARY.md").read_text()
    listed = set(re.findall(r"\]\(([^)#]+\.md)\)", summary))
    pages = {p.name for p in SRC.glob("*.md")} - {"SUMMARY.md"}
    assert pages - listed == set(), f"pages missing from SUMMARY.md: {sorted(pages - listed)}"
    assert listed - pages == set(), f"SUMMARY.md lists missing pages: {sorted(listed - pages)}"


def test_readme_is_a_front_page():
    """The front page stays short, with the recommended command of each arm in its first
    screen (issue 25)."""
    readme = REPO / "README.md"
    if not SRC.is_dir():
        pytest.skip(f"SKIPPED: {SRC} not found (installed without the sources)")
    lines = readme.read_text().splitlines()
    assert len(lines) <= 300, f"README.md has {len(lines)} lines (at most 300)"
    first_screen = "\n".join(lines[:50])
    # The command lines the snippets run, continued lines joined.
    runs = [" ".join(line.split()) for b in fenced_blocks(readme) if runnable(b)
            for line in b.code.replace("\\\n", " ").splitlines()]
    recommended = "--preset dvrk"
    for arm in ("psm", "mtm"):
        command = f"dvrk-ident fit LOG --robot {arm} {recommended}"
        assert command in first_screen, f"README.md's first screen lacks `{command}`"
        assert any(r.startswith("dvrk-ident fit ") and f"--robot {arm} " in r and recommended in r
                   for r in runs), f"no snippet of README.md runs `{command}` on a log"
