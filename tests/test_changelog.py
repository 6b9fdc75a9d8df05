"""The version means something: the newest release of CHANGELOG.md is the package's version."""

import re
from pathlib import Path

import cmpsim

ROOT = Path(__file__).resolve().parents[1]


def _releases() -> list[str]:
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    return re.findall(r"^## \[([^\]]+)\]", text, flags=re.MULTILINE)


def test_the_newest_release_of_the_changelog_is_the_package_version():
    releases = _releases()
    assert releases[0] == "Unreleased", releases  # where the next changes are written
    assert releases[1] == cmpsim.__version__, f"CHANGELOG.md has no section for {cmpsim.__version__}: {releases}"
    assert "0.1.0" in releases


def test_the_changelog_is_on_the_docs_site_and_linked_from_the_readme():
    page = (ROOT / "docs" / "changelog.md").read_text(encoding="utf-8")
    assert '--8<-- "CHANGELOG.md"' in page
    assert "changelog.md" in (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    assert "CHANGELOG.md" in (ROOT / "README.md").read_text(encoding="utf-8")
