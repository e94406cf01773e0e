"""Scene editor: language edits on the 4D representation (static and dynamic), with history."""

from .editor import SceneEditor, scene_centre
from .select import CandidateScorer, MaskAgreementScorer, Selection, Selector

__all__ = ["SceneEditor", "scene_centre", "Selector", "Selection", "CandidateScorer", "MaskAgreementScorer"]
