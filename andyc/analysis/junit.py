"""JUnit XML of `andyc test`'s outcomes (andyc.analysis.expectations): the format CI services read.

One <testsuite> per model file, one <testcase> per run and per check (classname the model file, name
its document path, expect[i] or expect[i].<check>), a <failure> with the message for each that does not
hold; a model that cannot be loaded or compiled is one <testcase> with an <error>. Built with
xml.etree, so text from a model file is escaped as XML needs.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from andyc.errors import printable


def junit_xml(results: list) -> str:
    """results: [(file, outcomes, problems)] with outcomes of the model's expectations and problems the
    lines that stopped it (a model that does not load or compile); the XML text."""
    root = ET.Element("testsuites", name="andyc test")
    totals = {"tests": 0, "failures": 0, "errors": 0}
    for file, outcomes, problems in results:
        suite = ET.SubElement(root, "testsuite", name=printable(file))
        failures = errors = 0
        seconds = 0.0
        for o in outcomes:
            case = ET.SubElement(suite, "testcase", classname=printable(file), name=o.path,
                                 time=f"{o.seconds:.6f}")
            seconds += o.seconds
            if not o.ok:
                failures += 1
                failure = ET.SubElement(case, "failure", message=str(o), type=o.kind)
                failure.text = str(o)
        if problems:
            errors += 1
            case = ET.SubElement(suite, "testcase", classname=printable(file), name="model")
            error = ET.SubElement(case, "error", message=printable(problems[0]), type="model")
            error.text = "\n".join(printable(p) for p in problems)
        tests = len(outcomes) + (1 if problems else 0)
        suite.set("tests", str(tests))
        suite.set("failures", str(failures))
        suite.set("errors", str(errors))
        suite.set("time", f"{seconds:.6f}")
        totals["tests"] += tests
        totals["failures"] += failures
        totals["errors"] += errors
    for k, v in totals.items():
        root.set(k, str(v))
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"
