"""Values of command-line options, checked: finite numbers in range, NAME=VALUE items, lists of numbers,
method names, --stop-after's JUMP=N and --input's drives; and --set's split into parameters and inputs.

Every numeric option of andyc goes through these, so NaN, the infinities, zero, negative and absurd
values get click's usual `Error: Invalid value for '--opt': ...` and exit 2 before any work is done.
"""

from __future__ import annotations

import math

import click

from andyc.runtime.methods import METHODS


class Number(click.ParamType):
    """A finite number within bounds: NaN and the infinities are refused (click's FloatRange lets NaN pass,
    since every comparison with it is false)."""

    def __init__(self, low=None, high=None, low_open=False, high_open=False, integer=False):
        self.low, self.high, self.low_open, self.high_open, self.integer = low, high, low_open, high_open, integer
        self.name = "integer" if integer else "number"

    def convert(self, value, param, ctx):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            number = value
        else:
            try:
                number = int(value) if self.integer else float(value)
            except (TypeError, ValueError):
                self.fail(f"{value!r} is not {'a whole number' if self.integer else 'a number'}", param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        if self.low is not None and (number < self.low or (self.low_open and number == self.low)):
            self.fail(f"{value} is too small: give a value {'above' if self.low_open else 'of at least'} "
                      f"{self.low:g}", param, ctx)
        if self.high is not None and (number > self.high or (self.high_open and number == self.high)):
            self.fail(f"{value} is too large: give a value {'below' if self.high_open else 'of at most'} "
                      f"{self.high:g}", param, ctx)
        return number


POSITIVE = Number(0, low_open=True)
NON_NEGATIVE = Number(0)
COUNT = Number(1, 10**12, integer=True)
TOLERANCE = Number(0, 1, low_open=True, high_open=True)


def parse_sets(values, option: str = "--set") -> dict:
    """('m=2', 'g=9.8') -> {'m': 2.0, 'g': 9.8}; each value a finite number."""
    out = {}
    for item in values:
        name, sep, value = item.partition("=")
        try:
            if not sep:
                raise ValueError
            out[name.strip()] = float(value)
        except ValueError:
            raise click.BadParameter(f"'{item}' is not NAME=NUMBER", param_hint=option)
        if not math.isfinite(out[name.strip()]):
            raise click.BadParameter(f"'{item}': {value.strip()} is not a finite number", param_hint=option)
    return out


def split_sets(values: dict, input_names) -> tuple[dict, dict]:
    """--set's {name: value} as (parameters, inputs): a name in input_names is an input, any other a parameter
    (one the model lacks is refused where the parameters are used, as an unknown parameter)."""
    inputs = {name: value for name, value in values.items() if name in input_names}
    return {name: value for name, value in values.items() if name not in inputs}, inputs


def stop_counts(items) -> dict:
    """--stop-after's ('strike=2',) -> {'strike': 2}, each count a whole number of at least 1."""
    stops = {}
    for item in items:
        name, sep, count = item.partition("=")
        if not sep or not count.strip().isdigit() or int(count) < 1:
            raise click.BadParameter(f"'{item}' is not JUMP=N with N >= 1", param_hint="--stop-after")
        stops[name.strip()] = int(count)
    return stops


def input_drives(items) -> dict:
    """--input's ('F=2', 'G=-k*x', 'H=table.csv') -> {name: text}: a number, an expression or a CSV table (which
    andyc.simulate tells apart); each name once, a value that reads as a number finite."""
    inputs = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not value.strip():
            raise click.BadParameter(f"'{item}' is not NAME=VALUE", param_hint="--input")
        if name.strip() in inputs:
            raise click.BadParameter(f"input '{name.strip()}' given twice", param_hint="--input")
        try:
            number = float(value)
        except ValueError:
            number = 0.0
        if not math.isfinite(number):
            raise click.BadParameter(f"'{item}': {value.strip()} is not a finite number", param_hint="--input")
        inputs[name.strip()] = value.strip()
    return inputs


def method_names(text: str, option: str) -> list:
    """'rk4, DOP853' -> ['rk4', 'DOP853'], each one of andyc's METHODS."""
    names = [m.strip() for m in text.split(",") if m.strip()]
    unknown = [m for m in names if m not in METHODS]
    if unknown or not names:
        raise click.BadParameter(f"unknown method(s) {', '.join(unknown) or '(none given)'}; available: "
                                 f"{', '.join(METHODS)}", param_hint=option)
    return names


def floats(text: str | None, option: str) -> list | None:
    """'1e-3,2e-3' -> [0.001, 0.002]; 'geom:A:B:N' -> N values from A to B, evenly spaced in log. Every value
    a positive finite number, at most MAX_LIST of them."""
    import numpy as np

    if text is None:
        return None
    try:
        if text.startswith("geom:"):
            lo, hi, n = text[5:].split(":")
            lo, hi, n = float(lo), float(hi), int(n)
            if not 1 <= n <= MAX_LIST:
                raise click.BadParameter(f"'{text}': the count {n} must be from 1 to {MAX_LIST}", param_hint=option)
            values = [lo, hi] if n > 1 else [lo]
        else:
            values = [float(v) for v in text.split(",")]
    except ValueError:
        raise click.BadParameter(f"'{text}' is not a list of numbers (1e-3,2e-3) or geom:FROM:TO:COUNT",
                                 param_hint=option) from None
    bad = next((v for v in values if not (math.isfinite(v) and v > 0)), None)
    if bad is not None:
        raise click.BadParameter(f"'{text}': {bad:g} is not a positive finite number", param_hint=option)
    if len(values) > MAX_LIST:
        raise click.BadParameter(f"'{text}': {len(values)} values, past the limit of {MAX_LIST}", param_hint=option)
    return list(np.geomspace(lo, hi, n)) if text.startswith("geom:") else values


MAX_LIST = 10_000
