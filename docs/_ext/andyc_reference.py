"""Reference pages made by the build from what the code holds, so that they cannot drift (issue 45).

conf.py calls write_all(docs) before Sphinx reads the sources: the model file reference from the JSON Schemas,
every command and option from the click group, the status codes from their tables, the gallery from the shipped
models with their pictures (`andyc graph` of each, drawn here). The pages go to docs/generated/, which is not committed (.gitignore): the build is the only writer.
"""

from __future__ import annotations

import json
from pathlib import Path

import click
import yaml

ROOT = Path(__file__).resolve().parents[2]


def _text(value) -> str:
    """One table cell: no newlines or pipes, which would break a Markdown table."""
    return " ".join(str(value).split()).replace("|", "\\|") if value is not None else ""


def _type(node: dict) -> str:
    if "$ref" in node:
        name = node["$ref"].rsplit("/", 1)[-1]
        return f"[{name}](#def-{name.lower()})"
    if "type" in node:
        kinds = node["type"] if isinstance(node["type"], list) else [node["type"]]
        kind = " or ".join(kinds)
        if "items" in node and isinstance(node["items"], dict):
            kind += " of " + _type(node["items"])
        return kind
    for key in ("oneOf", "anyOf"):
        if key in node:
            return " or ".join(_type(option) for option in node[key])
    if "enum" in node:
        return "enum"
    if "const" in node:
        return f"`{node['const']}`"
    return "any"


def _properties(node: dict, prefix: str = "") -> list[str]:
    """A row per property, nested objects' properties below their parent's with a dotted name (`a.b`), those of
    an array's items with `a[].b`, those of each alternative (oneOf, anyOf, allOf) under the same name."""
    rows = []
    required = set(node.get("required", []))
    for name, sub in node.get("properties", {}).items():
        enum = ", ".join(f"`{v}`" for v in sub.get("enum", []))
        default = f"`{json.dumps(sub['default'])}`" if "default" in sub else ""
        rows.append(f"| `{prefix}{name}` | {_text(_type(sub))} | {'yes' if name in required else ''} | {default} "
                    f"| {enum} | {_text(sub.get('description', ''))} |")
        rows += _properties(sub, f"{prefix}{name}.")
    if isinstance(node.get("items"), dict):
        rows += _properties(node["items"], f"{prefix[:-1]}[]." if prefix else "[].")
    for key in ("oneOf", "anyOf", "allOf"):
        for option in node.get(key, []):
            rows += _properties(option, prefix)
    return rows


HEADER = ["| property | type | required | default | values | description |",
          "|---|---|---|---|---|---|"]


def schema_page(path: Path) -> str:
    schema = json.loads(path.read_text(encoding="utf-8"))
    lines = [f"# {schema.get('title', path.stem)}", "",
             f"Generated at build time from `andyc/schemas/{path.name}`.", "",
             _text(schema.get("description", "")), "", "## Top-level properties", "", *HEADER, *_properties(schema)]
    for name, node in schema.get("$defs", {}).items():
        lines += ["", f"({'def-' + name.lower()})=", f"## `{name}`", "", _text(node.get("description", "")), ""]
        lines += [f"Type: {_type(node)}", ""]
        rows = _properties(node)
        if rows:
            lines += [*HEADER, *rows]
    return "\n".join(lines) + "\n"


def _commands(group: click.Group, prefix: str):
    """Every command under the group, subgroups' commands with their full name ("andyc plot ...")."""
    context = click.Context(group, info_name=prefix)
    for name in group.list_commands(context):
        command = group.get_command(context, name)
        yield f"{prefix} {name}", command
        if isinstance(command, click.Group):
            yield from _commands(command, f"{prefix} {name}")


def cli_page() -> str:
    from andyc.cli import main   # the click group that the console script andyc.cli:run calls
    lines = ["# Command line", "", "Generated at build time from the click commands (`andyc.cli:main`, "
             "run by the `andyc` script).", ""]
    for full, command in _commands(main, "andyc"):
        lines += [f"## `{full}`", "", "```text", command.get_usage(click.Context(command, info_name=full)), "```",
                  "", _text(command.help or ""), ""]
        options = [p for p in command.params if isinstance(p, click.Option)]
        arguments = [p for p in command.params if isinstance(p, click.Argument)]
        if arguments:
            lines += ["Arguments: " + ", ".join(f"`{a.human_readable_name}`" for a in arguments), ""]
        if options:
            lines += ["| option | help |", "|---|---|"]
            for option in options:
                names = ", ".join(f"`{o}`" for o in [*option.opts, *option.secondary_opts])
                lines.append(f"| {names} | {_text(option.help or '')} |")
            lines.append("")
    return "\n".join(lines) + "\n"


def status_page() -> str:
    from andyc.numerics import status as numeric
    from andyc.runtime import status as runtime
    lines = ["# Status codes and messages", "",
             "Generated at build time from `andyc.numerics.status.MESSAGES` (why a compiled function failed) and "
             "`andyc.runtime.status.OUTCOMES` (a run's outcome, one per sweep point).", "",
             "## Compiled functions' status", "", "| code | message |", "|---|---|"]
    # code spans: the messages as the program prints them (no smart quotes, no "--" made a dash)
    lines += [f"| {code} | `{_text(message)}` |" for code, message in sorted(numeric.MESSAGES.items())]
    lines += ["", "## Run outcomes", "", "| code | outcome |", "|---|---|"]
    lines += [f"| {code} | {_text(name)} |" for code, name in sorted(runtime.OUTCOMES.items())]
    return "\n".join(lines) + "\n"


def _picture(stem: str, docs: Path) -> str | None:
    """A picture already in docs/ made from this model (view_<model>_t*.png), if there is one."""
    found = sorted(docs.glob(f"view_{stem}_t*.png"))
    return found[0].name if found else None


def graph_pictures(out: Path) -> None:
    """out/<model>.png: `andyc graph` of every shipped model (its frame tree and, for a hybrid model, its
    automaton), drawn again when the model file is newer than its picture."""
    import andyc
    from andyc.plot.graph import plot_graph

    out.mkdir(parents=True, exist_ok=True)
    for path in sorted((ROOT / "models").glob("*.yaml")):
        picture = out / f"{path.stem}.png"
        if not picture.is_file() or picture.stat().st_mtime < path.stat().st_mtime:
            plot_graph(andyc.load(path), picture)


def gallery_page(docs: Path) -> str:
    lines = ["# Gallery", "", "Every shipped model in `models/`, generated at build time from the YAML files: "
             "its command and its expectations (`expect:`, checked by `andyc test models/`).", ""]
    for path in sorted((ROOT / "models").glob("*.yaml")):
        model = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        simulate = {"method": "rk4", **(model.get("simulate") or {})}      # (what its simulate: sets, else rk4)
        commands = [f"andyc sim models/{path.name}   # " + ", ".join(f"{k} {v}" for k, v in simulate.items())]
        if model.get("expect"):
            commands.append(f"andyc test models/{path.name}   # its expectations, below")
        lines += [f"## {model.get('name', path.stem)}", "", _text(model.get("description", "")), "",
                  "```console", *commands, "```", ""]
        picture = _picture(path.stem, docs)
        if picture:
            lines += [f"![{path.stem} in andyc view](../{picture})", ""]
        lines += [f"```{{image}} graphs/{path.stem}.png", f":alt: andyc graph of {path.stem}", ":width: 55%",
                  "```", ""]
        expectations = model.get("expect") or []
        if expectations:
            lines += ["Expectations:", "", "```yaml", yaml.safe_dump(expectations, sort_keys=False).strip(), "```", ""]
    return "\n".join(lines) + "\n"


def write_all(docs: Path) -> None:
    out = docs / "generated"
    out.mkdir(exist_ok=True)
    graph_pictures(out / "graphs")
    pages = {"cli.md": cli_page(), "status.md": status_page(), "gallery.md": gallery_page(docs)}
    for schema in sorted((ROOT / "andyc" / "schemas").glob("*.schema.json")):
        pages[schema.name.replace(".schema.json", ".md")] = schema_page(schema)
    for name, text in pages.items():
        target = out / name
        # rewritten only when changed, so that Sphinx's incremental build does not reread every page
        if not target.is_file() or target.read_text(encoding="utf-8") != text:
            target.write_text(text, encoding="utf-8")
