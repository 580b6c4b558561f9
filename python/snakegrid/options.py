"""The method's parameters: the library's table (snakegrid_option_info) and setting values.

Nothing about a parameter is known here: names, kinds, defaults and ranges all come from the
library loaded, and the library parses and checks every value (a bad one raises SnakegridError
naming the option), so this module can never disagree with the command line.
"""

import ctypes
from dataclasses import dataclass
from typing import Optional, Tuple

from . import _abi, _library


@dataclass(frozen=True)
class Option:
    """One row of the parameter table. `minimum`/`maximum` are None for an open-ended range and
    `minimum_open`/`maximum_open` say whether the bound itself is excluded; for lists they
    bound each element and `list_min`/`list_max` the length."""

    name: str
    kind: str  # real, integer, bool, choice, real_list or pair_list
    default: str  # as text that options accept back ("none" for an unset optional)
    optional: bool
    minimum: Optional[float]
    minimum_open: bool
    maximum: Optional[float]
    maximum_open: bool
    range: str
    integer_bits: int
    list_min: int
    list_max: int
    choices: Tuple[str, ...]
    unit: str
    group: str
    group_title: str
    advanced: bool
    summary: str
    help: str


def options(library=None):
    """Every parameter of the method, in the table's order (grouped by the step of the method)."""
    lib = library or _library.load()
    rows = []
    for index in range(lib.c.snakegrid_option_count()):
        row = _abi.Option()
        lib.check(lib.c.snakegrid_option_info(index, ctypes.byref(row)))

        def text(value):
            return value.decode("utf-8")

        rows.append(
            Option(
                name=text(row.name),
                kind=_abi.OPTION_KINDS[row.kind],
                default=text(row.default_value),
                optional=row.optional,
                minimum=row.minimum if row.has_minimum else None,
                minimum_open=row.minimum_open,
                maximum=row.maximum if row.has_maximum else None,
                maximum_open=row.maximum_open,
                range=text(row.range),
                integer_bits=row.integer_bits,
                list_min=row.list_min,
                list_max=row.list_max,
                choices=tuple(c for c in text(row.choices).split("|") if c),
                unit=text(row.unit),
                group=text(row.group),
                group_title=text(row.group_title),
                advanced=row.advanced,
                summary=text(row.summary),
                help=text(row.help),
            )
        )
    return rows


def option_text(value):
    """A Python value as option text: True/False, numbers, None ("none"), text as it is, and
    sequences of numbers or of (x, y) pairs as the comma-separated lists options take."""
    if value is None:
        return "none"
    if hasattr(value, "tolist"):  # a numpy array or scalar: its Python values
        value = value.tolist()
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return value
    if isinstance(value, float):
        return repr(float(value))  # the shortest text that reads back as the same double
    if isinstance(value, (list, tuple)):
        return ",".join(
            ":".join(option_text(v) for v in item) if isinstance(item, (list, tuple))
            else option_text(item)
            for item in value
        )
    return str(value)


def set_options(lib, handle, values):
    """Sets {name: value} on an options handle; the library refuses what it cannot take."""
    for name, value in values.items():
        lib.check(lib.c.snakegrid_options_set(
            handle, _library.c_text(name, "the option name"),
            _library.c_text(option_text(value), f"option {name}: the value")))


def check_options(library=None, **values):
    """Raises SnakegridError, naming the option, for a value the library would refuse: a host
    checks a dialog's values with it before reading any feature."""
    lib = library or _library.load()
    with lib.handle("options") as handle:
        set_options(lib, handle, values)
