"""The version of what the generator produces, part of every on-disk cache key of its clips and scenes."""

from __future__ import annotations

__all__ = ["GENERATOR_VERSION"]

# Bump when a change to parsing, composition, assets, trajectories or rendering changes the clip or
# scene a (prompt, seed, GenerationConfig) gives, so entries cached before the change are generated
# again instead of served. (Version 1 was the key's fixed value before it was tied to the generator.)
GENERATOR_VERSION = 2
