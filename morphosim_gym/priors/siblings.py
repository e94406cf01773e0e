"""Depth of an object whose ground contact is hidden, from a sibling of the same size.

Numbered instances of one planned object ("sheep 1", "sheep 2") share one real size. Where one
walks behind the other, the one behind has its feet hidden: the few columns whose pixel below is
still free are its outline's ends, with ground far behind them, and its contact depth reads too far
(the example's rear sheep: 5.9 m where it walks at 4.45 m). Its sibling in front shows its contact;
the same real width over both masks' pixel widths gives the one behind a depth in proportion.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from .depth import below_lowest

__all__ = ["base_name", "hidden_share", "whole_width", "depths_from_siblings"]


def base_name(label: str) -> str:
    """"sheep 2" -> "sheep": the planned object a numbered instance is one of (other labels as given)."""
    head, _, tail = label.rpartition(" ")
    return head if head and tail.isdigit() else label


def hidden_share(mask: np.ndarray, others: np.ndarray) -> float:
    """Share of a mask's [H, W] columns whose pixel just below its lowest one is `others` [H, W]
    (another object in front hides its contact there); 0 for an empty mask."""
    c, below = below_lowest(mask)
    return float(others[below, c].mean()) if len(c) else 0.0


def whole_width(mask: np.ndarray, others: np.ndarray) -> int | None:
    """Columns a mask [H, W] spans, when both ends are its own: None where an end touches the
    image border or has another object (`others` [H, W]) right beside it."""
    cols = np.flatnonzero(mask.any(axis=0))
    if len(cols) == 0 or cols[0] == 0 or cols[-1] == mask.shape[1] - 1:
        return None
    for c, side in ((cols[0], cols[0] - 1), (cols[-1], cols[-1] + 1)):
        if others[mask[:, c], side].any():
            return None
    return int(cols[-1] - cols[0] + 1)


def depths_from_siblings(masks: np.ndarray, depths: Mapping[int, np.ndarray], groups: Sequence[Sequence[int]],
                         hidden: float = 0.5) -> dict[int, np.ndarray]:
    """[T] depths per instance, with the frames where more than `hidden` of an instance's contact
    is hidden by other objects replaced by a sibling's depth (same group: one planned size) times
    the sibling's pixel width over its own, the median over the siblings whose contact shows, and
    never nearer than the nearest sibling hiding it. Hidden frames without such a sibling or
    without whole widths take it interpolated in time from the replaced ones, where there are
    any; other frames keep their depth."""
    out = {k: np.array(v, dtype=np.float64) for k, v in depths.items()}
    t = len(masks)
    for group in groups:
        members = [k for k in group if k in depths]
        if len(members) < 2:
            continue
        covered = {k: np.zeros(t, bool) for k in members}      # hidden in that frame
        scaled_at = {k: np.zeros(t, bool) for k in members}    # and given a sibling's scale
        for i in range(t):
            objects = masks[i] > 0
            seen = {}
            for k in members:
                m = masks[i] == k
                if m.any():
                    others = objects & ~m
                    seen[k] = (below_lowest(m), hidden_share(m, others), whole_width(m, others))
            for a, ((cols, below), share, width) in seen.items():
                covered[a][i] = share > hidden
                if share <= hidden or width is None:
                    continue
                scaled, front = [], []
                for b, (_, share_b, width_b) in seen.items():
                    if b == a or not np.isfinite(depths[b][i]):
                        continue
                    if share_b <= hidden and width_b is not None:
                        scaled.append(depths[b][i] * width_b / width)
                    if (masks[i][below, cols] == b).any():          # b lies just under a: in front of it
                        front.append(depths[b][i])
                if scaled:
                    out[a][i] = max(float(np.median(scaled)), max(front, default=0.0))
                    scaled_at[a][i] = True
        for a in members:
            # hidden frames without a whole width go on from the scaled ones, not from the far
            # contact (a depth jumping between the two within a clip)
            gap = covered[a] & ~scaled_at[a]
            if scaled_at[a].any() and gap.any():
                k = np.flatnonzero(scaled_at[a])
                out[a][gap] = np.interp(np.flatnonzero(gap), k, out[a][k])
    return out

