"""Scene-key overrides for sweeps: ``--set KEY=V1,V2,...`` on dotted TOML paths.

A key is a dotted path into the scene's TOML document: table keys by name, arrays of tables
by a zero-based index (``interactions.0.friction``, ``materials.glass.youngs_modulus``,
``simulation.rayleigh_fraction``). An override is applied to the parsed TOML dict *before*
validation, so the loader checks the result as it checks any scene file: a key the scene
format does not know, or a value it refuses, is a :class:`SceneError` naming the scene file,
the key and the reason (the message adds which ``--set`` it came from). A missing leaf (a key
the format allows but the scene leaves at its default, e.g. ``simulation.skin``) or a missing
table is created; an array index past the end, or indexing into something that is not an
array, is refused here.

Values are TOML values (``0.3``, ``true``, ``[0, 0, -9.81]``, ``"13 t/h"``); a value that is
not valid TOML is taken as a string, so ``simulation.precision=f32,f64`` and
``factories.0.mass_rate=13 t/h`` need no quotes. Values are separated by commas outside
brackets, braces and quotes.
"""
from __future__ import annotations

import copy
import itertools
import tomllib
from dataclasses import dataclass
from typing import Any, Iterable, Sequence

from ..errors import SceneError

DELETE = object()    # an override value that removes the key (used by tradeoffs, not the CLI)


@dataclass(frozen=True)
class SetSpec:
    """One ``--set``: a dotted key and the values it takes, in the order given."""
    key: str
    values: tuple


def split_values(text: str) -> list[str]:
    """``text`` split at the commas that are not inside brackets, braces or quotes."""
    parts, depth, quote, start = [], 0, "", 0
    i = 0
    while i < len(text):
        c = text[i]
        if quote:
            if c == "\\" and quote == '"':
                i += 1
            elif c == quote:
                quote = ""
        elif c in "\"'":
            quote = c
        elif c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        elif c == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
        i += 1
    parts.append(text[start:])
    return [p.strip() for p in parts]


def parse_value(token: str) -> Any:
    """A TOML value (number, boolean, string, array, inline table); anything that does not
    parse as TOML is the string itself."""
    try:
        return tomllib.loads(f"v = {token}")["v"]
    except tomllib.TOMLDecodeError:
        return token


def parse_set(arg: str, source: str = "--set") -> SetSpec:
    """``KEY=V1,V2,...`` -> :class:`SetSpec`; a malformed argument is a SceneError (exit 2)."""
    key, eq, rest = arg.partition("=")
    key = key.strip()
    if not eq or not key:
        raise SceneError(source, key or arg, f"expected KEY=V1,V2,... (a dotted scene key, e.g. "
                                             f"interactions.0.friction=0.3,0.5), got {arg!r}")
    if any(not part for part in key.split(".")):
        raise SceneError(source, key, "an empty part in the dotted key")
    tokens = split_values(rest)
    if any(t == "" for t in tokens):
        raise SceneError(source, key, f"an empty value in {rest!r} (values are separated by "
                                      "commas)")
    return SetSpec(key, tuple(parse_value(t) for t in tokens))


def combinations(sets: Sequence[SetSpec], zip_: bool = False) -> list[dict[str, Any]]:
    """The runs a list of ``--set``s asks for, as ordered ``{key: value}`` dicts: the cross
    product (first key varying slowest), or with ``zip_`` the i-th value of every key together
    (all must have as many values). No sets: one run with no override."""
    if not sets:
        return [{}]
    keys = [s.key for s in sets]
    if len(set(keys)) != len(keys):
        dup = next(k for k in keys if keys.count(k) > 1)
        raise SceneError("--set", dup, "given twice; give all its values in one --set")
    if zip_:
        n = {len(s.values) for s in sets}
        if len(n) != 1:
            raise SceneError("--set", sets[0].key,
                             "--zip needs the same number of values for every key, got "
                             + ", ".join(f"{s.key}: {len(s.values)}" for s in sets))
        rows = zip(*(s.values for s in sets))
    else:
        rows = itertools.product(*(s.values for s in sets))
    return [dict(zip(keys, row)) for row in rows]


def _loader_key(parts: Iterable[str]) -> str:
    """The loader's spelling of a dotted key: ``interactions.0.friction`` ->
    ``interactions[0].friction``."""
    out = ""
    for p in parts:
        out = f"{out}[{p}]" if p.isdigit() and out else (f"{out}.{p}" if out else p)
    return out


def apply(doc: dict, overrides: dict[str, Any], source: str) -> dict:
    """A deep copy of the TOML document ``doc`` with ``overrides`` ({dotted key: value}) set.
    Structural problems (an index past the end, a key through a value that is not a table)
    are SceneErrors naming ``source`` and the key."""
    doc = copy.deepcopy(doc)
    for key, value in overrides.items():
        parts = key.split(".")
        node: Any = doc
        for depth, part in enumerate(parts):
            last = depth == len(parts) - 1
            here = ".".join(parts[:depth + 1])
            if isinstance(node, list):
                if not part.isdigit():
                    raise SceneError(source, key, f"'{'.'.join(parts[:depth])}' is an array "
                                                  f"of {len(node)}: index it with a number "
                                                  f"(0 - {len(node) - 1}), not '{part}'")
                i = int(part)
                if i >= len(node):
                    raise SceneError(source, key, f"index {i} is past the end: the scene has "
                                                  f"{len(node)} entries in "
                                                  f"'{'.'.join(parts[:depth])}'")
                if last:
                    node[i] = value
                else:
                    node = node[i]
            elif isinstance(node, dict):
                if last:
                    if value is DELETE:
                        node.pop(part, None)
                    else:
                        node[part] = value
                else:
                    if part not in node:
                        node[part] = [] if parts[depth + 1].isdigit() else {}
                    node = node[part]
            else:
                raise SceneError(source, key, f"'{'.'.join(parts[:depth])}' is a value "
                                              f"({node!r}), not a table: cannot set '{here}'")
    return doc


def to_text(doc: dict) -> str:
    """The TOML text of ``doc`` (tomli-w; comments of the original file are not kept)."""
    import tomli_w
    return tomli_w.dumps(doc)


def overridden_text(text: str, overrides: dict[str, Any], source: str) -> str:
    """The scene ``text`` with ``overrides`` applied and validated by the loader (a SceneError
    names the key and, when it comes from an override, which one)."""
    if not overrides:
        return text
    new = to_text(apply(tomllib.loads(text), overrides, source))
    check(new, overrides, source)
    return new


def check(text: str, overrides: dict[str, Any], source: str, base_dir=None):
    """Validate ``text`` with the loader; returns the Scene. A SceneError is re-raised with
    the ``--set`` that caused it named, when one did."""
    from ..scene.loader import parse_scene
    try:
        return parse_scene(text, source=source, base_dir=base_dir)
    except SceneError as err:
        culprit = _culprit(err.key, overrides)
        if culprit is None:
            raise
        raise SceneError(err.file, err.key, f"{err.reason} (from --set {culprit}="
                                            f"{_show(overrides[culprit])})") from None


def _culprit(loader_key: str, overrides: dict[str, Any]):
    """The override whose key is, contains or lies in the loader's ``loader_key``."""
    for key in overrides:
        lk = _loader_key(key.split("."))
        if loader_key == lk or loader_key.startswith(lk + ".") or loader_key.startswith(lk + "[") \
                or lk.startswith(loader_key + ".") or lk.startswith(loader_key + "["):
            return key
    return None


def _show(value: Any) -> str:
    if value is DELETE:
        return "(removed)"
    if isinstance(value, str):
        return value
    return to_text({"v": value}).partition("=")[2].strip()
