"""Exceptions of the public API."""

from __future__ import annotations

__all__ = ["CommandError", "EditError", "BackendUnavailableError"]


class CommandError(ValueError):
    """A command the parser could not turn into a valid plan; the message says what was not
    understood and what would be."""


class EditError(ValueError):
    """An edit that cannot be applied to the given scene (nothing matches, ambiguous target...);
    the scene is left unchanged."""


class BackendUnavailableError(RuntimeError):
    """An optional backend (gsplat on CUDA, diffusion weights, an LLM endpoint...) is not usable
    here; the message names what is missing and how to install it."""
