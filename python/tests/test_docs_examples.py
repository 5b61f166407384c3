"""Every YAML example in the docs, and every robot file in the repository, passes `situate check`.

A fenced block tagged `yaml` is a robot file when it starts with `robot:` and is checked whole;
any other is a fragment, checked inside a robot with the toy sonar and wheels (unless it has its
own `devices:`). Paths in the examples are relative to a robot file in a folder at the top of the
repository (such as `examples/`). A block tagged `yaml schema` shows a file's shape with
placeholders and is not checked; one tagged `yaml manifest` is a skill manifest, which `situate gen
c` must accept. So a doc example cannot rot: this test names the doc and line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import pytest
from support import REPO, build_library, situate

DOCS = sorted([REPO / "README.md", *REPO.glob("docs/**/*.md"), *REPO.glob("examples/**/*.md")])
FENCE = re.compile(r"^```yaml([^\n]*)\n(.*?)^```", re.MULTILINE | re.DOTALL)
FRAGMENT_HEAD = "\n".join(
    [
        "robot: docs",
        "devices:",
        "  - {name: sonar, type: toy.sonar}",
        "  - {name: wheels, type: toy.wheels}",
        "",
    ]
)


@dataclass(frozen=True)
class Block:
    doc: Path
    line: int  # of the block's first line in the doc
    tags: tuple[str, ...]
    text: str

    def __str__(self) -> str:
        return f"{self.doc.relative_to(REPO)}:{self.line}"


def blocks() -> list[Block]:
    found = []
    for doc in DOCS:
        source = doc.read_text()
        for m in FENCE.finditer(source):
            line = source.count("\n", 0, m.start(2)) + 1
            found.append(Block(doc, line, tuple(m.group(1).split()), m.group(2)))
    return found


BLOCKS = blocks()


def own_program(path: Path) -> bool:
    """Whether the robot file belongs to a program of its own (a Cargo package at or above it,
    under examples/: its skill types are that program's;
    crates/binaries/situate_cli/tests/extension.rs builds the program and checks the file with
    it)."""
    return any((d / "Cargo.toml").exists() for d in path.parents if REPO / "examples" in d.parents)


ROBOT_FILES = sorted(
    p
    for folder in ("examples", "demo")
    for p in (REPO / folder).rglob("*.yaml")
    if (p.read_text().lstrip().startswith("robot:") or "\nrobot:" in p.read_text())
    and not own_program(p)
)


@pytest.fixture(scope="module")
def root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A copy of the repository's top level made of links, with an empty `robots/` folder."""
    for lang in ("c", "cpp"):  # the libraries the examples name (built where they expect)
        build_library(lang)
    top = tmp_path_factory.mktemp("repo")
    for entry in REPO.iterdir():
        (top / entry.name).symlink_to(entry)
    (top / "robots").mkdir()
    return top


def test_the_docs_have_yaml_examples() -> None:
    # A guard for the scan itself: a broken pattern would pass every check below vacuously.
    assert len([b for b in BLOCKS if "schema" not in b.tags]) >= 6
    assert any(b.doc.name == "robot-files.md" and b.text.startswith("robot:") for b in BLOCKS)
    assert len(ROBOT_FILES) >= 3


@pytest.mark.parametrize(
    "block", [b for b in BLOCKS if not {"schema", "manifest"} & set(b.tags)], ids=str
)
def test_a_doc_example_passes_check(root: Path, block: Block) -> None:
    whole = block.text.startswith("robot:")
    has_devices = re.search(r"^devices:", block.text, re.MULTILINE) is not None
    head = "" if whole or has_devices else FRAGMENT_HEAD
    if not whole and has_devices:
        head = "robot: docs\n"
    path = root / "robots" / "example.yaml"
    path.write_text(head + block.text)
    result = situate("check", str(path))
    # Map the temporary file's lines back to the doc's.
    offset = block.line - 1 - head.count("\n")

    def to_doc(m: re.Match[str]) -> str:
        return f"{block.doc.relative_to(REPO)}:{int(m.group(1)) + offset}:"

    report = re.sub(re.escape(str(path)) + r":(\d+):", to_doc, result.stderr)
    assert result.returncode == 0, f"the example at {block} fails `situate check`:\n{report}"


@pytest.mark.parametrize("block", [b for b in BLOCKS if "manifest" in b.tags], ids=str)
def test_a_doc_manifest_generates(tmp_path: Path, block: Block) -> None:
    path = tmp_path / "manifest.yaml"
    path.write_text(block.text)
    result = situate("gen", "c", str(path), "-o", str(tmp_path))
    assert result.returncode == 0, f"the manifest at {block} fails `situate gen`:\n{result.stderr}"


@pytest.mark.parametrize("path", ROBOT_FILES, ids=lambda p: str(p.relative_to(REPO)))
def test_a_robot_file_in_the_repository_passes_check(root: Path, path: Path) -> None:
    result = situate("check", str(path))
    assert result.returncode == 0, (
        f"{path.relative_to(REPO)} fails `situate check`:\n{result.stderr}"
    )
