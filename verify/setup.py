"""Builds keel-verify with the files it shares with the rest of Keel.

The JSON Schemas (``config/schema/``), the example missions (``config/*.yaml``) and the
TLA+ specs (``spec/``: modules, models, mutants, trace modules, the manifest) stay where
they are in the repository. A wheel carries a copy of them in ``keel_verify/_data/``,
laid out as in the repository, where ``keel_verify.resources`` finds them when no
checkout is around. An sdist carries the same copy, so that a wheel built from it has it
too. An editable install copies nothing: it reads the checkout.

Everything else (name, version, dependencies, entry point) is in ``pyproject.toml``.
"""

from __future__ import annotations

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.command.sdist import sdist

HERE = Path(__file__).resolve().parent
REPOSITORY = HERE.parent
PACKAGED = Path("keel_verify") / "_data"

# What a package carries, relative to the repository root.
SHARED = (
    "config/schema/*.json",
    "config/schema/README.md",
    "config/*.yaml",
    "spec/manifest.json",
    "spec/*.tla",
    "spec/*.cfg",
    "spec/*.md",
    "spec/mutants/*.tla",
    "spec/trace/*.tla",
)
# Files a complete copy must hold (a build that would miss one fails).
REQUIRED = (
    "config/schema/mission.schema.json",
    "config/schema/image.schema.json",
    "config/prototype3.yaml",
    "spec/manifest.json",
)


def _source_root() -> Path:
    """The repository around verify/, or the copy an sdist carries."""
    for root in (REPOSITORY, HERE / PACKAGED):
        if (root / "spec" / "manifest.json").is_file():
            return root
    raise SystemExit(
        "keel-verify: build it from a Keel checkout (spec/ and config/ beside verify/) "
        "or from its sdist"
    )


def shared_files() -> list[tuple[Path, Path]]:
    """(source, path relative to keel_verify/_data) of every shared file."""
    root = _source_root()
    files = [(source, source.relative_to(root))
             for pattern in SHARED for source in sorted(root.glob(pattern)) if source.is_file()]
    present = {str(relative) for _, relative in files}
    missing = [name for name in REQUIRED if name not in present]
    if missing:
        raise SystemExit(f"keel-verify: {root} lacks {', '.join(missing)}")
    return files


class BuildPyWithSharedFiles(build_py):
    """build_py, plus the shared files under keel_verify/_data/."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return  # an editable install reads the checkout itself
        for source, relative in shared_files():
            target = Path(self.build_lib) / PACKAGED / relative
            self.mkpath(str(target.parent))
            self.copy_file(str(source), str(target))

    def get_outputs(self, include_bytecode: bool = True) -> list[str]:
        outputs = list(super().get_outputs(include_bytecode))
        if not getattr(self, "editable_mode", False):
            outputs += [str(Path(self.build_lib) / PACKAGED / relative)
                        for _, relative in shared_files()]
        return outputs


class SdistWithSharedFiles(sdist):
    """sdist, plus the shared files under keel_verify/_data/."""

    def make_release_tree(self, base_dir: str, files: list[str]) -> None:
        super().make_release_tree(base_dir, files)
        for source, relative in shared_files():
            target = Path(base_dir) / PACKAGED / relative
            self.mkpath(str(target.parent))
            self.copy_file(str(source), str(target))


setup(cmdclass={"build_py": BuildPyWithSharedFiles, "sdist": SdistWithSharedFiles})
