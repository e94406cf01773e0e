"""Fixtures of the language tests: small duck-typed scenes and one shared embedding model."""

from __future__ import annotations

from dataclasses import dataclass

import pytest


@dataclass(frozen=True)
class Obj:
    id: int
    name: str
    category: str
    role: str = "object"
    color: tuple | None = None


class FakeScene:
    """What `parse` needs of a scene: `.objects` with `.name`, `.category` (and `.id`, `.role`)."""

    def __init__(self, *specs: str | tuple) -> None:
        objs = []
        for i, s in enumerate(specs):
            if isinstance(s, tuple):
                objs.append(Obj(i, *s))
            else:
                bg = s in ("ground", "water", "road", "sky", "grass", "snow", "sand")
                objs.append(Obj(i, s, s, "background" if bg else "object"))
        self.objects = objs


@pytest.fixture
def scene_factory():
    return FakeScene


@pytest.fixture(scope="session")
def minilm():
    """The real all-MiniLM-L6-v2, loaded once for the whole test session (~8 s)."""
    from morphosim_gym.language import embeddings

    embeddings.load()
    return embeddings
