"""Exceptions of the public API."""

from __future__ import annotations

__all__ = ["CommandError", "EditError", "BackendUnavailableError", "TargetNotFoundError", "AmbiguousTargetError",
           "UnknownBackendError"]


class CommandError(ValueError):
    """A command the parser could not turn into a valid plan; the message says what was not
    understood and what would be."""


class EditError(ValueError):
    """An edit that cannot be applied to the given scene (nothing matches, ambiguous target...);
    the scene is left unchanged."""


class BackendUnavailableError(RuntimeError):
    """An optional backend (gsplat on CUDA, diffusion weights, an LLM endpoint...) is not usable
    here; the message names what is missing and how to install it."""


class TargetNotFoundError(CommandError, EditError):
    """An edit names something the scene does not have ("delete the giraffe" in a street scene);
    the message lists the scene's objects. Both a `CommandError` (from `parse(text, scene)`) and an
    `EditError` (from `sim.edit`)."""


class AmbiguousTargetError(CommandError, EditError):
    """An edit target matches objects of different categories about equally well; the message
    asks which one (say "all ..." to edit every match)."""


class UnknownBackendError(ValueError):
    """A backend name (generator, parser, renderer...) that no registry knows, or a
    ``"module:factory"`` spec naming no factory; the message lists the known names."""
