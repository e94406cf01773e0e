"""Scene editor: language edits on the 4D representation (static and dynamic), with history."""

from .editor import SceneEditor
from .select import CandidateScorer, MaskAgreementScorer, Selection, Selector

__all__ = ["SceneEditor", "Selector", "Selection", "CandidateScorer", "MaskAgreementScorer"]
