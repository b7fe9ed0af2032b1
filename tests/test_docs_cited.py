"""Every document the tests and the code cite is in the repository (issue 41): a citation of a page that is not
here cannot be checked by a reader."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CITED = re.compile(r"\bdocs/[A-Za-z0-9_./-]+\.(?:md|png|txt)")


def cited_paths():
    for folder in ("tests", "andyc"):
        for source in sorted((ROOT / folder).rglob("*.py")):
            for number, line in enumerate(source.read_text(encoding="utf-8").splitlines(), 1):
                for path in CITED.findall(line):
                    yield source.relative_to(ROOT), number, path


def test_the_tests_and_the_code_cite_documents():
    # the check below must have something to check: the reference cases are cited by many tests
    assert any(path == "docs/reference-cases.md" for _, _, path in cited_paths())


def test_every_cited_document_exists():
    missing = [f"{source}:{number}: {path}" for source, number, path in cited_paths() if not (ROOT / path).is_file()]
    assert not missing, "cited but not in the repository:\n" + "\n".join(missing)


def test_no_citation_of_the_old_names_outside_the_repository():
    # REFERENCE-CASES and DESIGN.md were documents next to the repository, not in it
    old = re.compile(r"REFERENCE-CASES|DESIGN\.md")
    sources = [s for folder in ("tests", "andyc") for s in sorted((ROOT / folder).rglob("*.py"))]
    sources += [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md")), *sorted((ROOT / "models").rglob("*.yaml")),
                *sorted((ROOT / "bench").rglob("*.py"))]
    found = [f"{source}:{number}" for source in sources if source.name != "test_docs_cited.py"
             for number, line in enumerate(source.read_text(encoding="utf-8").splitlines(), 1) if old.search(line)]
    assert not found, found


def test_the_readme_names_the_commands_and_its_links_into_docs_exist():
    # README is a first visit's page (issue 45): the two commands, the docs site, and links that lead somewhere
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    for command in ("make demo", "make test", "make docs"):
        assert command in readme, command
    links = re.findall(r"\]\((docs/[^)#]+)", readme)
    assert "docs/model-file.md" in links        # the security section, "Model files from anyone", is there
    assert "Model files from anyone" in (ROOT / "docs" / "model-file.md").read_text(encoding="utf-8")
    missing = [link for link in links if not (ROOT / link).is_file()]
    assert not missing, missing
