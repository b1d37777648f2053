"""YAML round trip, nested dict conversion and command-line overrides of the config dataclasses.

Every value read from YAML or from a `--set` override is checked against the field's type before the
dataclass sees it, so that a wrong type fails with the field's name, the value and what is allowed
(``AgentConfig.hidden_sizes (agent.hidden_sizes) must be a list of integers >= 1, e.g. [128, 128, 128], got
'abc' (a string)``) rather than deep inside a range check. All errors are `ValueError`.
"""
from __future__ import annotations

import dataclasses
import difflib
import math
import re
import typing
from dataclasses import fields, is_dataclass
from pathlib import Path
from typing import Any, get_type_hints

import yaml

CHECKOUT = Path(__file__).resolve().parents[2]  # the repository a checkout's package lives in

# PyYAML reads 1e-5 and 1e5 (no dot) as strings (YAML 1.1); such numeric strings are accepted for numbers
_NUMBER = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")
_KINDS = {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "a list",
          tuple: "a list", dict: "a mapping", type(None): "null"}


def to_dict(cfg: Any) -> Any:
    """Dataclass → plain dict (tuples become lists), for YAML and checkpoints."""
    if is_dataclass(cfg):
        return {f.name: to_dict(getattr(cfg, f.name)) for f in fields(cfg)}
    if isinstance(cfg, (tuple, list)):
        return [to_dict(v) for v in cfg]
    return cfg


def _got(value: Any) -> str:
    kind = _KINDS.get(type(value), type(value).__name__)
    return f"got {value!r} ({kind})"


def _number(value: Any, where: str, integer: bool = False) -> int | float:
    """An int or float field's value; bools and non-numeric strings are refused."""
    v = value
    if isinstance(v, str) and _NUMBER.fullmatch(v.strip()):
        v = float(v)
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"{where} must be {'an integer' if integer else 'a number'}, {_got(value)}")
    if integer:
        if isinstance(v, float):
            if not (math.isfinite(v) and v.is_integer()):
                raise ValueError(f"{where} must be an integer, {_got(value)}")
            v = int(v)
        return v
    return float(v)


def _convert(value: Any, hint: Any, where: str) -> Any:
    """`value` as the type `hint` of a config field (bool, int, float, str, Optional[float], Tuple[...])."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin is typing.Union:  # Optional[X]
        if value is None:
            return None
        inner = [a for a in args if a is not type(None)]
        try:
            return _convert(value, inner[0], where)
        except ValueError:
            raise ValueError(f"{where} must be null (None) or {_KINDS.get(inner[0], inner[0])}, "
                             f"{_got(value)}") from None
    if origin in (tuple, typing.Tuple):
        item = args[0] if args else Any
        variable = len(args) == 2 and args[1] is Ellipsis
        what = "integers" if item is int else "numbers"
        example = {int: "[128, 128, 128]", float: "[1.0, 1.2]"}.get(item, "[...]")
        n = None if variable else len(args)
        if isinstance(value, (list, tuple)):
            if n is not None and len(value) != n:
                raise ValueError(f"{where} must be a list of {n} {what}, got {list(value)!r} ({len(value)} values)")
            try:
                return tuple(_convert(v, item, where) for v in value)
            except ValueError:
                pass
        shape = f"a list of {n} {what}" if n is not None else f"a list of {what}, e.g. {example}"
        raise ValueError(f"{where} must be {shape}, {_got(value)}")
    if hint is bool:
        if not isinstance(value, bool):
            raise ValueError(f"{where} must be true or false, {_got(value)}")
        return value
    if hint is int:
        return _number(value, where, integer=True)
    if hint is float:
        return _number(value, where)
    if hint is str:
        if not isinstance(value, str):
            raise ValueError(f"{where} must be a string (quote it in YAML, e.g. '\"{value}\"'), {_got(value)}")
        return value
    return value


def from_dict(cls: type, data: dict | None, _path: str = "") -> Any:
    """Plain dict → dataclass `cls`; unknown keys and values of the wrong type raise `ValueError` naming the
    field (`Class.field (dotted.path)`), the value and what is allowed; missing keys take defaults."""
    if data is None:
        data = {}
    upgrade = getattr(cls, "upgrade_fields", None)  # a class that reads another form of its fields maps it
    if upgrade is not None and isinstance(data, dict):
        data = upgrade(data)
    if not isinstance(data, dict):
        where = f"the {_path} section" if _path else f"a {cls.__name__}"
        raise ValueError(f"{where} must be a mapping of field: value ({cls.__name__} fields: "
                         f"{', '.join(f.name for f in fields(cls))}), {_got(data)}")
    hints = get_type_hints(cls)
    known = [f.name for f in fields(cls)]
    unknown = sorted(set(data) - set(known), key=str)
    if unknown:
        near = {u: difflib.get_close_matches(str(u), known, n=1) for u in unknown}
        hint = "; ".join(f"{u!r}: did you mean {m[0]!r}?" for u, m in near.items() if m)
        raise ValueError(f"unknown {cls.__name__} field(s) {unknown}{f' in {_path}' if _path else ''}"
                         f"{f' ({hint})' if hint else ''}; allowed: {sorted(known)}")
    kwargs = {}
    defaults = {f.name: f for f in fields(cls)}
    for name, value in data.items():
        hint, path = hints[name], f"{_path}.{name}" if _path else name
        if is_dataclass(hint):
            # a partial section changes the fields it names of the parent's default for it (e.g. EnvConfig's
            # walk, whose trot lifts 0.10 m, not WalkConfig()'s 0.15 m): the file overrides, as --set does
            base = _default_of(defaults[name])
            if isinstance(value, dict) and is_dataclass(base):
                value = merged(to_dict(base), value)
            kwargs[name] = from_dict(hint, value, path)
        else:
            where = f"{cls.__name__}.{name}" + (f" ({path})" if _path else "")
            kwargs[name] = _convert(value, hint, where)
    return cls(**kwargs)


def _default_of(f: dataclasses.Field) -> Any:
    """A dataclass field's default value (None where it has none)."""
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return None


def merged(base: dict, changes: dict) -> dict:
    """`base` with `changes` laid over it, nested mappings merged key by key."""
    out = dict(base)
    for k, v in changes.items():
        out[k] = merged(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


PRESET_KEYS = ("base", "summary", "phases", "extract")  # keys only a preset file has (`cyberdog.config.preset`)


def read_config_file(path: str | Path) -> Any:
    """The YAML content of a config file. A missing file raises `FileNotFoundError` (`not_found`'s line), a folder
    or bad YAML `ValueError`."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"config {path} is a folder, expected a YAML file")
    if not path.is_file():
        raise FileNotFoundError(not_found(path, "config file"))
    try:
        return yaml.safe_load(path.read_text())
    except yaml.YAMLError as e:
        raise ValueError(f"config {path} is not valid YAML: {' '.join(str(e).split())}") from None


def is_preset(data: Any) -> bool:
    """Whether a config file's content (`read_config_file`) is a training preset (it has a key of PRESET_KEYS)."""
    return isinstance(data, dict) and bool(set(PRESET_KEYS) & set(data))


def read_settings(path: str | Path, what: str, allowed: list[str]) -> Any:
    """`read_config_file` of a file of `what`'s settings (sections `allowed`); a training preset is a `ValueError`
    saying which file it is."""
    data = read_config_file(path)
    if is_preset(data):
        raise ValueError(f"{path} is a training preset (train.py --config), not a {what} file; allowed in one: "
                         f"{', '.join(allowed)}")
    return data


def load_fields(cls: type, path: str | Path) -> Any:
    """Read a YAML file of `cls`'s fields (`read_settings`: a missing file raises `FileNotFoundError`, a folder,
    bad YAML, a preset or bad values `ValueError` naming the file). (`cyberdog.config.load` also reads a preset
    file as its ExperimentConfig.)"""
    data = read_settings(path, cls.__name__, [f.name for f in fields(cls)])
    try:
        return from_dict(cls, data)
    except ValueError as e:
        raise ValueError(f"{path}: {e}") from None


def save(cfg: Any, path: str | Path) -> None:
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as f:
        yaml.safe_dump(to_dict(cfg), f, sort_keys=False)


def add_override_option(parser, example: str, extra_help: str = "") -> None:
    """The one `--set SECTION.FIELD=VALUE` option of the command lines (train.py, evaluate.py) on `parser` (or an
    argument group): values parsed as YAML, into `args.overrides` in the order given; several values after one
    --set and repeated --set flags add up, and a later assignment of a field wins (`override`)."""
    parser.add_argument("--set", dest="overrides", action="extend", nargs="+", default=[],
                        metavar="SECTION.FIELD=VALUE",
                        help=f"override a config field, value parsed as YAML, e.g. --set {example}; repeatable, "
                             f"and one --set may take several (default: none){extra_help}")


def override(cfg: Any, assignments: list[str]) -> Any:
    """Apply command-line overrides such as ``gait.speed=1.2`` (values parsed as YAML)."""
    data = to_dict(cfg)
    for item in assignments:
        if "=" not in item:
            raise ValueError(f"override {item!r} must look like section.field=value")
        key, raw = item.split("=", 1)
        node = data
        parts = key.strip().split(".")
        for i, p in enumerate(parts[:-1]):
            if not isinstance(node, dict) or p not in node:
                raise ValueError(f"override {item!r}: no section {p!r}{_choices(node, p, parts[:i])}")
            node = node[p]
        if not isinstance(node, dict) or parts[-1] not in node:
            raise ValueError(f"override {item!r}: no field {parts[-1]!r}{_choices(node, parts[-1], parts[:-1])}")
        try:
            node[parts[-1]] = yaml.safe_load(raw)
        except yaml.YAMLError as e:
            raise ValueError(f"override {item!r}: the value is not valid YAML ({' '.join(str(e).split())})") from None
    return from_dict(type(cfg), data)


def _choices(node: Any, name: str, parent: list[str]) -> str:
    if not isinstance(node, dict):
        return f" ({'.'.join(parent)} is a value, not a section)"
    near = difflib.get_close_matches(name, [str(k) for k in node], n=1)
    where = f" in {'.'.join(parent)}" if parent else ""
    return (f" (did you mean {near[0]!r}?)" if near else "") + f"; allowed{where}: {', '.join(map(str, node))}"


def replace(cfg: Any, **changes: Any) -> Any:
    return dataclasses.replace(cfg, **changes)


def not_found(path: str | Path, what: str) -> str:
    """One line for a `what` file (e.g. "config file") that is not at `path`: a relative path is read from the
    current folder, so where the repository's own copy exists the line names the checkout to run from."""
    path = Path(path)
    line = f"{what} {path} does not exist"
    if not path.is_absolute():
        line += f" in the current folder ({Path.cwd()})"
        in_checkout = CHECKOUT / path
        if in_checkout.is_file():
            line += f"; it is in the checkout: run from {CHECKOUT}, or give {in_checkout}"
    return line
