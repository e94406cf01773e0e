"""`WordTable`: handlers of constructions, keyed by the words the constructions start with.

    table = WordTable()

    @table.on("from", "to")
    def _from_to(reader, i, state): ...    # index after what it read, or None: not this construction

    for handler in table.handlers_for(word): ...   # in registration order

A handler registered with `any_word` is tried for every word (it tests the word itself, e.g. a
vocabulary lookup). Digits ("3", "2.5") are looked up under the key `NUMBER`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterable
from typing import Any

from .tokens import is_number

__all__ = ["NUMBER", "WordTable"]

NUMBER = "<number>"


class WordTable:
    """An ordered list of (start words, handler); `handlers_for(word)` is cached per word."""

    def __init__(self) -> None:
        self._entries: list[tuple[frozenset[str] | None, Callable[..., Any]]] = []
        self.handlers_for = functools.lru_cache(maxsize=8192)(self._handlers_for)

    def on(self, *words: str | Iterable[str]) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
        """Register a handler for the words it can start with (strings or collections of them)."""
        keys: set[str] = set()
        for w in words:
            keys.update([w] if isinstance(w, str) else w)

        def register(fn: Callable[..., Any]) -> Callable[..., Any]:
            self._entries.append((frozenset(keys), fn))
            self.handlers_for.cache_clear()
            return fn
        return register

    def any_word(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        """Register a handler tried for every word."""
        self._entries.append((None, fn))
        self.handlers_for.cache_clear()
        return fn

    def _handlers_for(self, word: str) -> tuple[Callable[..., Any], ...]:
        key = NUMBER if is_number(word) else word
        return tuple(fn for keys, fn in self._entries if keys is None or key in keys)
