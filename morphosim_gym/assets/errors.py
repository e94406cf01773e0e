"""The asset layer's error and warning types."""

from __future__ import annotations

__all__ = ["AssetError", "AssetWarning"]


class AssetError(ValueError):
    """An asset that cannot be used (missing or broken file, file too large, a `.ply` without a
    required field...); the message names the file and the problem."""


class AssetWarning(UserWarning):
    """Something was skipped or replaced by a fallback (a broken catalogue, an unreadable texture,
    a damaged cache entry); the message names the file."""
