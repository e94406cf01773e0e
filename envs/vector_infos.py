"""A vector step's info dict: every env's info batched as Gymnasium's `VectorEnv._add_info` does
(one array per key, a boolean mask `_key` per key, nested dicts batched alike), with the same
arrays, dtypes, masks and key order, at less cost per step.

- `add_info`: `VectorEnv._add_info` itself, for one env's info (resets).
- `batch_infos`: every (env index, info) of a step at once, key by key.
- `InfoBatch`: the same result built env by env while a step runs, so that the batch's last
  env leaves only the masks to make (the vector env fills it as each env finishes, while the
  render helpers still render the next envs' views).
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

__all__ = ["InfoBatch", "add_info", "batch_infos"]


def add_info(vector_infos: dict, env_info: dict, env_num: int, n: int) -> dict:
    """`VectorEnv._add_info` of `n` envs (same arrays, dtypes, masks and key order), without its
    per-key throwaway mask array and repeated look-ups."""
    for key, value in env_info.items():
        if key == "final_obs":
            array = vector_infos.get(key)
            if array is None:
                array = np.full(n, fill_value=None, dtype=object)
            array[env_num] = value
        elif isinstance(value, dict):
            array = add_info(vector_infos.get(key, {}), value, env_num, n)
        else:
            array = vector_infos[key] if key in vector_infos else _info_array(value, n)
            array[env_num] = value
        mask_key = f"_{key}"
        mask = vector_infos.get(mask_key)
        if mask is None:
            mask = np.zeros(n, dtype=np.bool_)
        mask[env_num] = True
        vector_infos[key], vector_infos[mask_key] = array, mask
    return vector_infos


def batch_infos(entries: list, n: int) -> dict:
    """`add_info` of each (env index, info) in order, key by key: one array and one mask per key
    for all envs instead of per env (same arrays, dtypes, masks and key order). Infos of the same
    keys and value types fill the arrays at once (`InfoBatch`); others go column by column
    (`_batch_columns`)."""
    batch = InfoBatch(n)
    for i, info in entries:
        batch.add(i, info)
    return batch.result()


def _batch_columns(entries: list, n: int) -> dict:
    """`batch_infos` of infos whose keys or value types differ: key by key over the envs that
    have it (a key whose values mix dicts and non-dicts takes `add_info` env by env)."""
    columns: dict = {}
    for i, info in entries:
        for key, value in info.items():
            column = columns.get(key)
            if column is None:
                columns[key] = [(i, value)]
            else:
                column.append((i, value))
    out: dict = {}
    for key, column in columns.items():
        kinds = {isinstance(v, dict) for _, v in column}
        if key == "final_obs":
            array = np.full(n, fill_value=None, dtype=object)
            for i, v in column:
                array[i] = v
        elif len(kinds) > 1:
            sequential: dict = {}
            for i, info in entries:
                sequential = add_info(sequential, info, i, n)
            return sequential
        elif kinds == {True}:
            array = batch_infos(column, n)
        else:
            array = _info_column(column, n)
        mask = np.zeros(n, dtype=np.bool_)
        mask[[i for i, _ in column]] = True
        out[key], out[f"_{key}"] = array, mask
    return out


class _Level:
    """One dict level of an `InfoBatch`: its keys (the first info's, in order) and per key either
    a batch array being filled, a nested `_Level`, or None for a nested dict whose keys differ
    between envs (batched at the end by `batch_infos`)."""

    __slots__ = ("keys", "slots", "kinds")

    def __init__(self, info: dict, n: int) -> None:
        self.keys = list(info)
        self.slots: dict = {}
        self.kinds: dict = {}
        for key, value in info.items():
            if key == "final_obs":
                self.slots[key], self.kinds[key] = np.full(n, fill_value=None, dtype=object), None
            elif type(value) is dict:
                self.slots[key], self.kinds[key] = _Level(value, n), dict
            else:
                self.slots[key] = _info_array(value, n)
                self.kinds[key] = (type(value), value.shape, value.dtype) if type(value) is np.ndarray else type(value)

    def fill(self, i: int, info: dict) -> bool:
        """Env i's values into the arrays; False (some may be written) when its keys or a value's
        type (an array's shape or dtype) differ from the first info's at this level."""
        if type(info) is not dict or list(info) != self.keys:
            return False
        kinds = self.kinds
        for key, slot in self.slots.items():
            value = info[key]
            kind = kinds[key]
            if kind is dict:
                if type(value) is not dict:
                    return False
                if slot is not None and not slot.fill(i, value):
                    self.slots[key] = None                   # keys differ between envs: batched at the end
                continue
            if kind is not None:                             # "final_obs" takes any value
                if type(kind) is tuple:
                    if type(value) is not np.ndarray or (value.shape, value.dtype) != kind[1:]:
                        return False
                elif type(value) is not kind:
                    return False
            slot[i] = value
        return True

    def result(self, present: np.ndarray, entries: list, path: tuple, n: int) -> dict:
        out: dict = {}
        for key in self.keys:
            slot = self.slots[key]
            if type(slot) is _Level:
                slot = slot.result(present, entries, path + (key,), n)
            elif slot is None:
                slot = batch_infos([(i, _at(info, path + (key,))) for i, info in entries], n)
            out[key], out[f"_{key}"] = slot, present.copy()
        return out


class InfoBatch:
    """`batch_infos` of a step's (env index, info) pairs, filled env by env as they are `add`ed.

    While every info has the first one's keys (in order, at every level but nested dicts whose
    keys differ between envs, such as "id_to_name") and values of the first one's types, each
    `add` writes its values into the batch arrays at once and `result` only makes the masks;
    otherwise `result` batches all the infos at the end key by key, in the order given there.
    Either way the result is what `add_info` env by env gives (same arrays, dtypes, masks, key
    order).
    """

    def __init__(self, n: int) -> None:
        self.n = n
        self._level: Optional[_Level] = None
        self._ok = True
        self._present = np.zeros(n, dtype=np.bool_)
        self._entries: list = []

    def add(self, i: int, info: dict) -> None:
        """Env i's info (each env at most once a step)."""
        self._entries.append((i, info))
        self._present[i] = True
        if not self._ok:
            return
        if self._level is None:
            if type(info) is not dict:
                self._ok = False
                return
            self._level = _Level(info, self.n)
        self._ok = self._level.fill(i, info)

    def result(self, order: Optional[list] = None) -> dict:
        """The batched infos; `order` (env indices) is the order `batch_infos` takes them in when
        the infos did not all match (default: the order they were added in)."""
        entries = self._entries
        if order is not None:
            position = {i: k for k, (i, _) in enumerate(entries)}
            entries = [entries[position[i]] for i in order]
        if not self._ok or self._level is None:
            return _batch_columns(entries, self.n)
        return self._level.result(self._present, entries, (), self.n)


def _at(info: dict, path: tuple) -> Any:
    for key in path:
        info = info[key]
    return info


def _info_array(value: Any, n: int) -> np.ndarray:
    """The batch array `VectorEnv._add_info` makes for an info value: numbers and bools by their
    type, arrays by shape and dtype, anything else as objects."""
    if type(value) in (int, float, bool) or issubclass(type(value), np.number):
        return np.zeros(n, dtype=type(value))
    if isinstance(value, np.ndarray):
        return np.zeros((n, *value.shape), dtype=value.dtype)
    return np.full(n, fill_value=None, dtype=object)


def _info_column(column: list, n: int) -> np.ndarray:
    """The batch array of one info key from its (env index, value) pairs, as `_info_array` and
    one assignment per env make it; values of the first one's type (and shape) go in at once."""
    first = column[0][1]
    array = _info_array(first, n)
    kind = type(first)
    if array.dtype != object and all(type(v) is kind for _, v in column) and (
            kind is not np.ndarray or all(v.shape == first.shape and v.dtype == first.dtype for _, v in column)):
        values = [v for _, v in column]
        array[[i for i, _ in column]] = np.stack(values) if kind is np.ndarray else values
        return array
    for i, v in column:
        array[i] = v
    return array
