"""Optional learned quality scores: CLIP text-image similarity and Q-Align, from local models only.

Neither model ships in a PyPI package, so both are used only when a local model folder is
configured (argument, or `$MORPHOSIM_CLIP_MODEL` / `$MORPHOSIM_QALIGN_MODEL`); nothing is
downloaded. `load_clip` / `load_qalign` return `(scorer, None)` or `(None, reason)`, and the
quality report prints "unavailable" with the reason.

- CLIP: a Hugging Face `CLIPModel` folder with its tokenizer; the score is the cosine
  similarity of the image and prompt embeddings (images resized to the model's input size and
  normalised with CLIP's mean and std here, so no image-processor dependency is needed).
- Q-Align: a Q-Align checkpoint folder whose remote code provides `model.score(images,
  task_=..., input_="image")` (as the published one-align model does); gives "quality" and
  "aesthetic" on a 1-5 scale. Untested here: no such model is available offline.
  Its Python files run when it loads, so a folder that ships code is refused unless asked
  with ``trust_remote_code=True`` (``morphosim quality --trust-remote-code``).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Callable, Optional, Sequence

import numpy as np

__all__ = ["ClipScorer", "load_clip", "load_qalign", "remote_code_files", "CLIP_ENV", "QALIGN_ENV"]

CLIP_ENV = "MORPHOSIM_CLIP_MODEL"
QALIGN_ENV = "MORPHOSIM_QALIGN_MODEL"
_CLIP_MEAN = np.array([0.48145466, 0.4578275, 0.40821073])
_CLIP_STD = np.array([0.26862954, 0.26130258, 0.27577711])


def _model_dir(path: Optional[str], env: str) -> tuple[Optional[Path], Optional[str]]:
    text = path or os.environ.get(env)
    if not text:
        return None, f"no local model configured (--{'clip' if env == CLIP_ENV else 'qalign'}-model or ${env})"
    p = Path(text).expanduser()
    if not p.is_dir():
        return None, f"model folder {str(p)!r} not found"
    return p, None


class ClipScorer:
    """Cosine similarity between CLIP embeddings of an image and a text.

    Args:
        path: a folder with a `CLIPModel` and its tokenizer (`save_pretrained` layout).
    """

    def __init__(self, path: str | os.PathLike) -> None:
        import torch
        from transformers import CLIPModel, CLIPTokenizer

        self._torch = torch
        self.model = CLIPModel.from_pretrained(str(path), local_files_only=True).eval()
        self.tokenizer = CLIPTokenizer.from_pretrained(str(path), local_files_only=True)
        self.size = int(self.model.config.vision_config.image_size)

    def _pixels(self, image: np.ndarray) -> Any:
        import cv2

        a = np.asarray(image)
        a = a.astype(np.float64) / 255.0 if a.dtype == np.uint8 else a.astype(np.float64)
        a = cv2.resize(a[..., :3], (self.size, self.size), interpolation=cv2.INTER_AREA)
        a = (a - _CLIP_MEAN) / _CLIP_STD
        return self._torch.from_numpy(a.transpose(2, 0, 1)[None].astype(np.float32))

    def __call__(self, image: np.ndarray, text: str) -> float:
        """Cosine similarity in [-1, 1] of an RGB image [H, W, 3] and a text."""
        torch = self._torch
        tokens = self.tokenizer([text], padding=True, truncation=True, return_tensors="pt")
        with torch.no_grad():
            img = self.model.get_image_features(pixel_values=self._pixels(image))
            txt = self.model.get_text_features(input_ids=tokens["input_ids"], attention_mask=tokens["attention_mask"])
        img = getattr(img, "pooler_output", img)
        txt = getattr(txt, "pooler_output", txt)
        return float(torch.nn.functional.cosine_similarity(img, txt).item())


def load_clip(path: Optional[str] = None) -> tuple[Optional[ClipScorer], Optional[str]]:
    """A `ClipScorer` from `path` (or `$MORPHOSIM_CLIP_MODEL`), or None and why not."""
    folder, why = _model_dir(path, CLIP_ENV)
    if folder is None:
        return None, why
    try:
        return ClipScorer(folder), None
    except Exception as exc:  # a broken or incompatible folder: report it, do not stop the report
        return None, f"could not load CLIP from {str(folder)!r}: {type(exc).__name__}: {exc}"


QAlignScore = Callable[[Sequence[np.ndarray], str], list]


def remote_code_files(folder: Path) -> list[str]:
    """What in a model folder would run as Python when transformers loads it: its ``.py`` files,
    and ``auto_map`` classes named by its ``config.json``."""
    import json

    found = sorted(p.name for p in Path(folder).glob("*.py"))
    try:
        config = json.loads((Path(folder) / "config.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        config = {}
    auto_map = config.get("auto_map") if isinstance(config, dict) else None
    if auto_map:
        found.append("config.json auto_map")
    return found


def load_qalign(path: Optional[str] = None, trust_remote_code: bool = False
                ) -> tuple[Optional[QAlignScore], Optional[str]]:
    """A Q-Align scorer `(images, task) -> scores` from `path` (or `$MORPHOSIM_QALIGN_MODEL`), or None
    and why not; `task` is "quality" or "aesthetic".

    Raises:
        ValueError: the folder ships Python code (Q-Align does) and `trust_remote_code` is False.
    """
    folder, why = _model_dir(path, QALIGN_ENV)
    if folder is None:
        return None, why
    code = remote_code_files(folder)
    if code and not trust_remote_code:
        raise ValueError(f"Expected --trust-remote-code (Python: trust_remote_code=True) to load the Q-Align model "
                         f"in {str(folder)!r}, found it off: the folder ships Python code that loading runs "
                         f"({', '.join(code[:5])}); pass it only if you trust that folder")
    try:
        from PIL import Image
        from transformers import AutoModelForCausalLM

        model = AutoModelForCausalLM.from_pretrained(str(folder), trust_remote_code=bool(trust_remote_code),
                                                     local_files_only=True)
    except Exception as exc:
        return None, f"could not load Q-Align from {str(folder)!r}: {type(exc).__name__}: {exc}"

    def score(images: Sequence[np.ndarray], task: str) -> list:
        pil = [Image.fromarray(np.asarray(i, dtype=np.uint8)) for i in images]
        return [float(s) for s in model.score(pil, task_=task, input_="image")]

    return score, None
