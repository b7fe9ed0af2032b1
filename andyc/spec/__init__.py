"""Spec stage: a YAML model (or a URDF) -> a validated Spec (schema, then meaning); every problem is a
diagnostic `FILE:LINE: PATH: what; fix`.

    load.py           read, check against the schema, build the sections in order around one Scope
    scope.py          the names declared so far, and what an expression may use
    frames.py, elements.py, constraints.py, hybrid.py, closed_form.py: one module per section
    expressions.py    the safe expression parser (a whitelist; never eval)
    schema_errors.py  the schema's errors in the loader's words;  suggest.py: "did you mean"
    model.py          the Spec and its parts;  meaning.py: the build key (what shapes the equations)
    urdf.py, urdfxml.py, urdfjoints.py, urdflinks.py: a URDF as the same model dictionary
    geometry.py       contacts made from shapes on a ground plane;  urdfcontacts.py: a URDF's (collision, limits)
    yamlpos.py        YAML with the line of every value
"""
