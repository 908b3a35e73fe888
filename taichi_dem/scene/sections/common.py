"""The loader's reading helpers, shared by every section: a value of a given type or unit,
or a SceneError naming the file, the dotted key and the reason."""
from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Optional

import numpy as np

from ...errors import SceneError
from ..keys import Key, Section
from ..keys import suggest as _suggest
from ..keys import type_name as _type_name
from ..units import parse_quantity, parse_vec3


class Reader:
    """The reading helpers: ``source`` (the file named in errors), ``base_dir`` (for
    relative paths), ``materials`` once [materials] is read."""

    def __init__(self, source: str, base_dir: Path):
        self.source = source
        self.base_dir = base_dir

    # -- generic helpers ----------------------------------------------------------------------
    def err(self, key: str, reason: str) -> SceneError:
        return SceneError(self.source, key, reason)

    def table(self, value: Any, key: str, what: str = "a table") -> dict:
        if not isinstance(value, dict):
            raise self.err(key, f"expected {what}, got {_type_name(value)}")
        return value

    def check_keys(self, tbl: dict, key: str, allowed, required=None) -> None:
        """Unknown keys of ``tbl`` (``allowed``: a declared Section, or names) with the
        closest suggested, then missing ``required`` keys (default: the Section's)."""
        if isinstance(allowed, Section):
            allowed.check(tbl, self.source, key, required)
            return
        Section(key, "", tuple(Key(k, "any", "") for k in allowed)).check(
            tbl, self.source, key, tuple(required or ()))

    def corners(self, t: dict, key: str):
        """``t["min"]``, ``t["max"]`` (m) of a box or the domain: max above min on every axis."""
        lo = self.vec3(t["min"], "length", f"{key}.min")
        hi = self.vec3(t["max"], "length", f"{key}.max")
        for i, ax in enumerate("xyz"):
            if not lo[i] < hi[i]:
                raise self.err(f"{key}.max", f"max must exceed min on every axis; on {ax}: "
                                             f"min = {lo[i]:g}, max = {hi[i]:g}")
        return lo, hi

    def q(self, value: Any, dimension: str, key: str) -> float:
        return parse_quantity(value, dimension, file=self.source, key=key)

    def positive(self, value: Any, dimension: str, key: str) -> float:
        x = self.q(value, dimension, key)
        if not x > 0.0:
            raise self.err(key, f"must be > 0, got {x:g}")
        return x

    def nonnegative(self, value: Any, dimension: str, key: str) -> float:
        x = self.q(value, dimension, key)
        if not x >= 0.0:
            raise self.err(key, f"must be >= 0, got {x:g}")
        return x

    def vec3(self, value: Any, dimension: str, key: str) -> tuple[float, float, float]:
        return parse_vec3(value, dimension, file=self.source, key=key)

    def direction(self, value: Any, key: str) -> tuple[float, float, float]:
        v = np.array(self.vec3(value, "dimensionless", key), dtype=float)
        n = float(np.linalg.norm(v))
        if not n > 0.0:
            raise self.err(key, "must be a nonzero vector (it is normalised on load)")
        return tuple(float(c) for c in v / n)

    def boolean(self, value: Any, key: str) -> bool:
        if not isinstance(value, bool):
            raise self.err(key, f"expected true or false, got {_type_name(value)}")
        return value

    def integer(self, value: Any, key: str) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.err(key, f"expected an integer, got {_type_name(value)}")
        return value

    def string(self, value: Any, key: str) -> str:
        """``value`` when it is a string without control characters (a NUL byte, a newline,
        an escape: nothing in a scene - a name, a path, a choice - can hold them)."""
        if not isinstance(value, str):
            raise self.err(key, f"expected a string, got {_type_name(value)}")
        char = control_character(value)
        if char is not None:
            raise self.err(key, f"contains the control character {char}; names, paths and "
                                "choices are printable text")
        return value

    def group_name(self, value: Any, key: str) -> str:
        """A wall's or body's name: it names an HDF5 group (/series/walls/<name>/...) and a
        Rerun entity, so a '/' would nest it in another group and '.' or '..' would name the
        group above; leading or trailing blanks would make two names look alike."""
        name = self.string(value, key)
        if not name.strip():
            raise self.err(key, "must be a non-empty name")
        if "/" in name or name in (".", "..") or name != name.strip():
            raise self.err(key, f"'{name}' cannot name a results group: no '/', not '.' or "
                                "'..', no leading or trailing blanks")
        return name

    def material_name(self, value: Any, key: str) -> str:
        name = self.string(value, key)
        if name not in self.materials:
            known = ", ".join(sorted(self.materials)) or "none (add a [materials.NAME] table)"
            raise self.err(key, f"unknown material '{name}'; {_suggest(name, self.materials)}"
                                f"defined materials: {known}")
        return name

    def array_of_tables(self, doc: dict, name: str) -> list[dict]:
        value = doc.get(name, [])
        if not isinstance(value, list):
            raise self.err(name, f"expected an array of tables ([[{name}]]), got "
                                 f"{_type_name(value)}")
        for i, item in enumerate(value):
            self.table(item, f"{name}[{i}]", f"a table ([[{name}]])")
        return value


def decode_utf8(data: bytes, file: str, key: str) -> str:
    """``data`` as text (a UTF-8 byte-order mark dropped, newlines as ``\n``); bytes that are
    not UTF-8 are a SceneError saying where."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        column = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        raise SceneError(file, key, f"not a UTF-8 text file ({e.reason}: byte "
                                    f"0x{data[e.start]:02x} at line {line}, column {column}); "
                                    "save it as UTF-8") from None
    return text.replace("\r\n", "\n").replace("\r", "\n")


def control_character(text: str) -> Optional[str]:
    """The first control character of ``text`` (Unicode category Cc: NUL, tab, newline,
    escape, DEL, ...) as ``U+XXXX (NAME)``, or None when there is none."""
    m = _CONTROL.search(text)
    if m is None:
        return None
    code = ord(m.group())
    return f"U+{code:04X}" + (f" ({_CONTROL_NAMES[code]})" if code in _CONTROL_NAMES else "")


_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f]")    # Unicode category Cc, all of it


_CONTROL_NAMES = {0x00: "a NUL byte", 0x09: "a tab", 0x0A: "a newline", 0x0D: "a carriage "
                  "return", 0x1B: "an escape", 0x7F: "a delete"}


def refuse_control_characters(doc: dict, source: str) -> None:
    """A SceneError for the first string value or table key of the parsed TOML ``doc`` that
    holds a control character (scene.loader calls it before any section is read: a NUL byte
    in a path or a name would otherwise reach the file system, HDF5 group names or the
    terminal). Walks the document without recursion."""
    stack: list[tuple[str, Any]] = [("", doc)]
    while stack:
        path, value = stack.pop()
        if isinstance(value, dict):
            for k, v in reversed(list(value.items())):
                char = control_character(k)
                if char is not None:
                    shown = k.encode("unicode_escape").decode()
                    raise SceneError(source, path or shown,
                                     f"the key or name \"{shown}\" contains the control "
                                     f"character {char}; names are printable text")
                stack.append((f"{path}.{k}" if path else k, v))
        elif isinstance(value, list):
            stack.extend((f"{path}[{i}]", v) for i, v in reversed(list(enumerate(value))))
        elif isinstance(value, str):
            char = control_character(value)
            if char is not None:
                raise SceneError(source, path, f"contains the control character {char}; "
                                               "names, paths and choices are printable text")
