"""andyc in other projects' CI: `andyc test`'s exit codes and lines, its JUnit XML, `--format json` (validated
against the schema shipped with the package) and `--format github` of check, build, sim and test, and the
one meaning of -o (the output; the build folder is --build-dir, the old spellings refused with a hint)."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from importlib import resources
from pathlib import Path

import jsonschema
import pytest

from tests.support.cli import invoke

ROOT = Path(__file__).resolve().parents[1]
BALL = (ROOT / "models" / "bouncing_ball.yaml").read_text()
BALL = BALL[:re.search(r"^expect:", BALL, re.M).start()]
# Two expectations: the first holds (three bounces by t = 2 s, see models/bouncing_ball.yaml), the second
# fails twice (four bounces asked for; a bounce loses energy, so the drift is not within 1e-6 J).
EXPECT = """\
expect:
  - {t_end: 2, jumps: {bounce: 3}}
  - t_end: 2
    jumps: {bounce: 4}
    energy_drift: 1.0e-6
"""




def output_schema() -> dict:
    return json.loads(resources.files("andyc").joinpath("schemas/andyc-output.schema.json").read_text())


def validated(stdout: str) -> dict:
    doc = json.loads(stdout)
    jsonschema.validate(doc, output_schema())
    return doc


@pytest.fixture(scope="module")
def place(tmp_path_factory):
    root = tmp_path_factory.mktemp("ci")
    (root / "models").mkdir()
    (root / "models" / "ball.yaml").write_text(BALL + EXPECT)
    (root / "models" / "bad.yaml").write_text(BALL.replace("mass: m}", "mass: -1}"))
    (root / "models" / "notes.txt").write_text("not a model")
    return root


def line_of(text: str, needle: str, occurrence: int = 1) -> int:
    return [n for n, line in enumerate(text.splitlines(), 1) if needle in line][occurrence - 1]


def test_andyc_test_lines_exit_code_and_junit(place):
    result = invoke("test", "models", "--build-dir", "build", "--junit", "out/junit.xml", cwd=place)
    assert result.exit_code == 1
    text = BALL + EXPECT
    failures = [line for line in result.stderr.splitlines() if ": expect[" in line]
    assert failures == [
        f"models/ball.yaml:{line_of(text, 'jumps: {bounce: 4}')}: expect[1].jumps: measured bounce 3 jumps, "
        "expected bounce 4",
        f"models/ball.yaml:{line_of(text, 'energy_drift')}: expect[1].energy_drift: measured largest "
        f"|E(t) - E(0)| {9.81 * (1 - 0.8 ** 6):.3g} J, expected <= 1e-06 J"]   # three bounces keep e^6 of m g h0
    mass = line_of(BALL, "mass: m}")
    assert f"models/bad.yaml:{mass}: bodies[0].mass: mass must be positive, got -1" in result.stderr
    # JUnit: one suite per model file (notes.txt is no model file), a case per run and per check.
    root = ET.parse(place / "out" / "junit.xml").getroot()
    suites = {s.get("name"): s for s in root.iter("testsuite")}
    assert set(suites) == {"models/ball.yaml", "models/bad.yaml"}
    ball = suites["models/ball.yaml"]
    cases = [c.get("name") for c in ball.iter("testcase")]
    assert cases == ["expect[0]", "expect[0].jumps", "expect[1]", "expect[1].jumps", "expect[1].energy_drift"]
    assert ball.get("tests") == "5" and ball.get("failures") == "2" and ball.get("errors") == "0"
    failed = [c.get("name") for c in ball.iter("testcase") if c.find("failure") is not None]
    assert failed == ["expect[1].jumps", "expect[1].energy_drift"]
    assert ball.find("testcase[@name='expect[1].jumps']/failure").get("message") == failures[0]
    bad = suites["models/bad.yaml"]
    assert bad.get("errors") == "1" and bad.find("testcase/error") is not None
    assert root.get("tests") == "6" and root.get("failures") == "2" and root.get("errors") == "1"


def test_andyc_test_json_and_github(place):
    result = invoke("test", "models/ball.yaml", "--build-dir", "build", "--format", "json", cwd=place)
    assert result.exit_code == 1
    doc = validated(result.stdout)
    assert doc["command"] == "test" and doc["ok"] is False and doc["exit_code"] == 1
    (model,) = doc["results"]
    assert [o["ok"] for o in model["outcomes"]] == [True, True, True, False, False]
    assert [p["path"] for p in doc["problems"]] == ["expect[1].jumps", "expect[1].energy_drift"]
    result = invoke("test", "models/ball.yaml", "--build-dir", "build", "--format", "github", cwd=place)
    line = line_of(BALL + EXPECT, "jumps: {bounce: 4}")
    assert (f"::error file=models/ball.yaml,line={line}::models/ball.yaml:{line}: expect[1].jumps: measured "
            "bounce 3 jumps, expected bounce 4") in result.stdout.splitlines()


def test_andyc_test_passes_and_usage(place):
    (place / "good.yaml").write_text(BALL + EXPECT.split("  - t_end: 2\n")[0])
    result = invoke("test", "good.yaml", "--build-dir", "build_good", cwd=place)     # (another file, same name)
    assert result.exit_code == 0, result.stderr
    assert "2 checks in 1 model: all hold" in result.stdout
    assert invoke("test", "missing.yaml", cwd=place).exit_code == 2


def test_check_json_and_github(place):
    result = invoke("check", "models/bad.yaml", str(ROOT / "models" / "pendulum_a01.yaml"), "--format", "json",
                   cwd=place)
    assert result.exit_code == 1
    doc = validated(result.stdout)
    (problem,) = doc["problems"]
    assert (problem["file"], problem["line"], problem["path"]) == ("models/bad.yaml", line_of(BALL, "mass: m}"),
                                                                     "bodies[0].mass")
    assert [r["ok"] for r in doc["results"]] == [False, True]
    assert result.stderr == ""                  # json: the one document, nothing else
    result = invoke("check", "models/bad.yaml", "--format", "github", cwd=place)
    assert result.exit_code == 1
    assert re.search(rf"^::error file=models/bad.yaml,line={line_of(BALL, 'mass: m}')}::models/bad.yaml:\d+: "
                     r"bodies\[0\].mass: mass must be positive", result.stdout, re.M)


def test_build_and_sim_json(place):
    result = invoke("build", "models/ball.yaml", "--build-dir", "build", "--format", "json", cwd=place)
    assert result.exit_code == 0, result.stderr
    doc = validated(result.stdout)
    assert doc["results"][0]["module"] == "build/bouncing_ball/bouncing_ball.py"
    result = invoke("sim", "models/ball.yaml", "--build-dir", "build", "-o", "out/ball.h5", "--format", "json",
                   cwd=place)
    assert result.exit_code == 0, result.stderr
    doc = validated(result.stdout)
    assert doc["results"][0]["outputs"] == ["out/ball.h5"] and doc["results"][0]["status"] == "finished"
    assert (place / "out" / "ball.h5").exists()
    # A run that stops (Zeno, at 4.06 s) is a run problem: exit 1, its status among the problems.
    result = invoke("sim", "models/ball.yaml", "--build-dir", "build", "-o", "out/zeno.h5", "--t-end", "5",
                   "--format", "json", cwd=place)
    assert result.exit_code == 1
    doc = validated(result.stdout)
    assert doc["ok"] is False and doc["problems"][0]["message"].startswith("stopped: Zeno behaviour")


@pytest.mark.parametrize("args, old", [(["build", "models/ball.yaml", "-o", "build"], "-o"),
                                       (["build", "models/ball.yaml", "--out-dir", "build"], "--out-dir"),
                                       (["sim", "models/ball.yaml", "--out-dir", "build"], "--out-dir")])
def test_the_old_build_folder_spellings_are_refused_with_a_hint(place, args, old):
    result = invoke(*args, cwd=place)
    assert result.exit_code == 2
    assert (f"{old} is no longer the build folder: give it as --build-dir DIR (-o/--out is the output "
            "everywhere") in result.stderr


def test_sim_o_is_the_run_file(place):
    result = invoke("sim", "models/ball.yaml", "--build-dir", "build", "-o", "build", cwd=place)
    assert result.exit_code == 2
    assert "unknown run file type ''; use .h5 or .csv (-o/--out is the run file; the build folder is --build-dir)" \
        in result.stderr


@pytest.mark.parametrize("args, says", [
    (["sim", "models/ball.yaml", "--dt", "-1", "--format", "json"], "--dt"),
    (["test", "missing.yaml", "--format=json"], "missing.yaml"),
    (["check", "--format", "json", "--bogus", "models/ball.yaml"], "--bogus"),
], ids=["bad-value", "missing-file", "unknown-option"])
def test_a_usage_error_under_format_json_is_a_json_document_too(place, args, says):
    """A command line refused before the command runs (exit 2) still prints the one JSON document a CI
    job parses, the message in it; click's message still goes to stderr, and stdout holds nothing else."""
    result = invoke(*args, cwd=place)
    assert result.exit_code == 2
    doc = validated(result.stdout)
    assert (doc["command"], doc["ok"], doc["exit_code"], doc["results"]) == (args[0], False, 2, [])
    (p,) = doc["problems"]
    assert says in p["message"] and says in result.stderr


def test_a_usage_error_without_format_json_prints_no_json(place):
    result = invoke("sim", "models/ball.yaml", "--dt", "-1", cwd=place)
    assert result.exit_code == 2 and result.stdout == ""
