"""The one YAML loader of configuration files (task specs, benchmark suites), safe against hostile input.

On top of `yaml.SafeLoader` (no Python objects) it refuses:

- more than `MAX_ALIASES` aliases, and documents whose aliases would expand to more than
  `MAX_NODES` nodes ("billion laughs": a few hundred bytes that expand to gigabytes), or that are
  recursive;
- a key given twice in one mapping (YAML silently keeps the last one);
- files over `MAX_BYTES` and documents nested deeper than Python can build.

Every problem is a `ConfigError` (a `ValueError`) whose message starts with the file, and, where
there is one, the line and the key. `expect` checks the type of one value the same way:
"tasks/x.yaml: key 'params.foo': expected a number, found 'abc'".
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import yaml

__all__ = ["MAX_ALIASES", "MAX_BYTES", "MAX_NODES", "ConfigError", "expect", "load_yaml_file", "load_yaml_text"]

MAX_ALIASES = 64            # our shipped files use none; anchors for a few shared blocks stay possible
MAX_NODES = 100_000         # a suite or task file has a few hundred
MAX_BYTES = 1 << 20


class ConfigError(ValueError):
    """A configuration file (or value) that cannot be used; the message names the file and the key."""


def _where(source: str, node: yaml.Node | None) -> str:
    return f"{source}: line {node.start_mark.line + 1}" if node is not None else source


class _StrictLoader(yaml.SafeLoader):
    """SafeLoader that counts aliases, bounds the expanded size and refuses duplicate keys."""

    source = "<yaml>"

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._aliases = 0

    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node:
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                event = self.peek_event()
                raise ConfigError(f"{self.source}: line {event.start_mark.line + 1}: more than {MAX_ALIASES} "
                                  f"YAML aliases (*name); write the values out")
        return super().compose_node(parent, index)

    def get_single_node(self) -> yaml.Node | None:
        node = super().get_single_node()
        if node is not None:
            _expanded_size(node, {}, set(), self.source)
        return node

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: dict[Any, yaml.Node] = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue
            key = self.construct_object(key_node, deep=True)
            try:
                first = seen.setdefault(key, key_node)
            except TypeError:
                raise ConfigError(f"{_where(self.source, key_node)}: a mapping key must be a plain value, "
                                  f"found {key!r}") from None
            if first is not key_node:
                raise ConfigError(f"{_where(self.source, key_node)}: duplicate key {key!r} (first on line "
                                  f"{first.start_mark.line + 1}); a key may appear once per mapping")
        return super().construct_mapping(node, deep=deep)


def _expanded_size(node: yaml.Node, sizes: dict[int, int], open_: set[int], source: str) -> int:
    """Nodes of the document with every alias written out (memoised: linear in the document)."""
    key = id(node)
    if key in sizes:
        return sizes[key]
    if key in open_:
        raise ConfigError(f"{_where(source, node)}: a recursive YAML alias (a node that contains itself)")
    open_.add(key)
    size = 1
    if isinstance(node, yaml.SequenceNode):
        size += sum(_expanded_size(child, sizes, open_, source) for child in node.value)
    elif isinstance(node, yaml.MappingNode):
        size += sum(_expanded_size(k, sizes, open_, source) + _expanded_size(v, sizes, open_, source)
                    for k, v in node.value)
    open_.discard(key)
    if size > MAX_NODES:
        raise ConfigError(f"{_where(source, node)}: the document expands to more than {MAX_NODES} values through "
                          f"its aliases (a 'billion laughs' file?); write the values out")
    sizes[key] = size
    return size


def load_yaml_text(text: str, source: str = "<yaml>") -> Any:
    """Parse one YAML document with the limits above; `ConfigError` naming `source` otherwise."""
    loader = _StrictLoader(text)
    loader.source = source
    try:
        return loader.get_single_data()
    except ConfigError:
        raise
    except yaml.YAMLError as exc:
        raise ConfigError(f"{source}: not valid YAML: {exc}") from None
    except RecursionError:
        raise ConfigError(f"{source}: nested too deeply") from None
    finally:
        loader.dispose()


def load_yaml_file(path: str | os.PathLike) -> Any:
    """Read and parse a YAML file (at most `MAX_BYTES`); `ConfigError` naming the file otherwise."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise ConfigError(f"{path}: {size} bytes, more than a configuration file needs ({MAX_BYTES})")
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    return load_yaml_text(text, str(path))


# ---------------------------------------------------------------- checking
def _is_number(v: Any) -> bool:
    if isinstance(v, bool):
        return False
    if isinstance(v, (int, float)):
        return True
    if isinstance(v, str):
        try:
            float(v)
        except ValueError:
            return False
        return True
    return False


_KINDS: dict[str, tuple[str, Callable[[Any], bool]]] = {
    "number": ("a number", _is_number),
    "finite number": ("a finite number", lambda v: _is_number(v) and math.isfinite(float(v))),
    "integer": ("an integer", lambda v: isinstance(v, int) and not isinstance(v, bool)),
    "string": ("a string", lambda v: isinstance(v, str)),
    "text": ("text (a string or a number)", lambda v: isinstance(v, (str, int, float)) and not isinstance(v, bool)),
    "mapping": ("a mapping", lambda v: isinstance(v, Mapping)),
    "list": ("a list", lambda v: isinstance(v, (list, tuple))),
    "bool": ("true or false", lambda v: isinstance(v, bool)),
}


def expect(value: Any, kind: str, key: str, source: str) -> Any:
    """`value` if it is of `kind` (see `_KINDS`), else a `ConfigError`
    "<source>: key '<key>': expected <kind>, found <value>"."""
    what, ok = _KINDS[kind]
    if not ok(value):
        shown = repr(value) if len(repr(value)) <= 80 else repr(value)[:77] + "..."
        raise ConfigError(f"{source}: key '{key}': expected {what}, found {shown}")
    return value
