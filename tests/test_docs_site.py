"""The documentation site builds with warnings as errors (a broken link or reference fails it: conf.py sets
nitpicky), and its generated reference pages name every schema key, every command and option and every status
code that the code defines (issue 45). One build for the whole file: a few seconds."""

import html
import json
import re
import subprocess
import sys
from pathlib import Path

import click
import pytest

pytest.importorskip("sphinx", reason="the docs site needs Sphinx: pip install -e '.[docs]'")
pytest.importorskip("myst_parser", reason="the docs site needs myst-parser: pip install -e '.[docs]'")

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                           str(ROOT / "docs"), str(out)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    return out


def page_text(site: Path, name: str) -> str:
    """The page's text as a reader sees it: tags dropped, entities decoded."""
    return html.unescape(re.sub(r"<[^>]+>", " ", (site / name).read_text(encoding="utf-8")))


def schema_paths(node, prefix: str = "") -> list:
    """Every key of a schema node at any depth, as the reference names it: `a.b` in an object, `a[].b` in an
    array's items, an alternative's (oneOf, anyOf, allOf) under the same name."""
    out = []
    for name, sub in node.get("properties", {}).items():
        out += [prefix + name, *schema_paths(sub, f"{prefix}{name}.")]
    if isinstance(node.get("items"), dict):
        out += schema_paths(node["items"], f"{prefix[:-1]}[]." if prefix else "[].")
    for key in ("oneOf", "anyOf", "allOf"):
        for option in node.get(key, []):
            out += schema_paths(option, prefix)
    return out


@pytest.mark.parametrize("schema", ["andyc-model", "andyc-output"])
def test_every_schema_key_is_in_the_model_reference(site, schema):
    """Each key, at any depth (a definition's own, an array's items': expect's states[].reference), as a whole
    name in the page: not a substring of another."""
    text = page_text(site, f"generated/{schema}.html")
    tree = json.loads((ROOT / "andyc" / "schemas" / f"{schema}.schema.json").read_text(encoding="utf-8"))
    paths = schema_paths(tree) + [p for node in tree.get("$defs", {}).values() for p in schema_paths(node)]
    missing = [p for p in paths if not re.search(rf"(?<![\w.\[\]]){re.escape(p)}(?![\w\[])", text)]
    assert len(paths) > len(tree["properties"]) and not missing, missing


def test_every_command_and_option_is_in_the_cli_reference(site):
    from andyc.cli import main
    text = page_text(site, "generated/cli.html")
    context = click.Context(main, info_name="andyc")
    missing = []
    for name in main.list_commands(context):
        command = main.get_command(context, name)
        if f"andyc {name}" not in text:
            missing.append(name)
        missing += [f"{name} {opt}" for p in command.params if isinstance(p, click.Option)
                    for opt in p.opts if opt not in text]
    assert main.list_commands(context) and not missing, missing
    assert not re.findall(r"\u2013[a-z][a-z-]*", text)      # (no option written --name in prose shown as an en dash)


def test_every_function_of_a_generated_module_is_in_the_api_reference(site):
    """The generated module's Python face (andyc_numerics/api.py: Functions), each public method documented."""
    from andyc.numerics.api import Functions

    page = (site / "api.html").read_text(encoding="utf-8")
    names = [n for n in vars(Functions) if not n.startswith("_") and callable(getattr(Functions, n))]
    missing = [n for n in names if f'id="andyc.numerics.api.Functions.{n}"' not in page]
    assert len(names) >= 15 and not missing, missing


def test_every_status_code_and_message_is_in_the_status_table(site):
    from andyc.numerics.status import MESSAGES
    from andyc.runtime.status import OUTCOMES
    text = " ".join(page_text(site, "generated/status.html").split())
    missing = [m for m in [*MESSAGES.values(), *OUTCOMES.values()] if " ".join(m.split()) not in text]
    assert not missing, missing


def test_the_gallery_lists_every_shipped_model_with_its_command(site):
    """Each model's run with the method its file names (simulate:), and `andyc test` where it has expectations."""
    import yaml

    text = " ".join(page_text(site, "generated/gallery.html").split())
    missing = []
    for path in sorted((ROOT / "models").glob("*.yaml")):
        model = yaml.safe_load(path.read_text(encoding="utf-8"))
        method = (model.get("simulate") or {}).get("method", "rk4")
        if not re.search(rf"andyc sim models/{re.escape(path.name)} # method {method}\b", text):
            missing.append(f"sim {path.name} ({method})")
        if model.get("expect") and f"andyc test models/{path.name}" not in text:
            missing.append(f"test {path.name}")
    assert not missing, missing


def test_the_gallery_shows_every_shipped_models_graph_drawn_by_the_build(site):
    page = (site / "generated" / "gallery.html").read_text(encoding="utf-8")
    images = dict(re.findall(r'<img alt="andyc graph of ([\w-]+)" src="([^"]+)"', page))
    assert sorted(images) == sorted(p.stem for p in (ROOT / "models").glob("*.yaml"))
    for stem, src in images.items():
        picture = (site / "generated" / src).resolve()
        assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", stem


def test_every_page_is_in_a_toctree(site):
    # Sphinx warns about a page in no toctree (a warning is an error here); this checks that the Background
    # pages are reachable from the front page.
    text = (site / "index.html").read_text(encoding="utf-8")
    for page in ("design", "reference-cases", "BENCHMARKS", "go1", "mutation", "ci", "getting-started"):
        assert f'href="{page}.html"' in text, page
