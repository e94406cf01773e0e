"""Quality of a reconstruction against its clip (and the clip's ground truth, for novel views).

Measured:
* input views: PSNR / SSIM of renders from the clip's cameras against its frames;
* novel views: the generation camera yawed by +-15 and +-30 degrees about the scene centre,
  renders of the reconstruction against renders of `clip.ground_truth` (evaluation only);
* per-object instance IoU of the rendered instance map against the clip's masks (input views);
* semantic feature field: for every object, the Gaussians whose decoded feature is most similar
  to that object's label embedding, against the instance each Gaussian was initialised from
  (precision and recall).
"""

from __future__ import annotations

import numpy as np

from ..metrics import iou, psnr, ssim
from ..render import render
from ..scene import GeneratedClip, Scene4D

__all__ = ["quality_report", "semantic_precision_recall", "NOVEL_YAWS", "format_report"]

NOVEL_YAWS = (-30.0, -15.0, 15.0, 30.0)


def semantic_precision_recall(scene: Scene4D) -> dict[str, dict[str, float]]:
    """Per object: precision and recall of "decoded feature nearest this object's label embedding"."""
    from ..language import embeddings

    if "semantic" not in scene.decoders or scene.gaussians.features is None:
        raise ValueError("Expected a scene with a semantic feature field, found none")
    names = [o.name for o in scene.objects]
    emb = embeddings.embed(names)
    similarity = scene.decoders["semantic"].similarity(scene.gaussians.features, emb)
    pred = np.asarray([scene.objects[k].id for k in np.argmax(similarity, axis=1)])
    truth = scene.gaussians.object_ids
    out = {}
    for o in scene.objects:
        p, t = pred == o.id, truth == o.id
        tp = float((p & t).sum())
        out[o.name] = {"precision": tp / max(float(p.sum()), 1.0), "recall": tp / max(float(t.sum()), 1.0)}
    return out


def quality_report(clip: GeneratedClip, scene: Scene4D, frame_stride: int = 4, seconds: float | None = None) -> dict:
    """Measure a reconstruction (see the module docstring); novel views need `clip.ground_truth`."""
    frames = list(range(0, clip.num_frames, max(1, frame_stride)))
    in_psnr, in_ssim, ious = [], [], {}
    by_name: dict[str, list[int]] = {}
    for o in scene.objects:
        by_name.setdefault(o.name, []).append(o.id)
    for i in frames:
        out = render(scene, clip.cameras[i], t=i / clip.fps)
        in_psnr.append(psnr(out.rgb, clip.frames[i]))
        in_ssim.append(ssim(out.rgb, clip.frames[i]))
        for inst, name in clip.labels.items():
            gt = clip.masks[i] == inst
            if gt.sum() < 4:
                continue
            # by name: a scene fitted to estimated priors numbers its instances its own way
            ious.setdefault(name, []).append(iou(np.isin(out.instance, by_name.get(name, [])), gt))
    report: dict = {
        "input": {"psnr": float(np.mean(in_psnr)), "ssim": float(np.mean(in_ssim)), "frames": len(frames)},
        "instance_iou": {k: float(np.mean(v)) for k, v in ious.items()},
        "gaussians": len(scene.gaussians),
    }
    gt = clip.ground_truth
    if gt is not None:
        centre = gt.centre()
        novel = {}
        for yaw in NOVEL_YAWS:
            ps, ss = [], []
            for i in frames:
                cam = clip.cameras[i].orbit(yaw, centre)
                a = render(scene, cam, t=i / clip.fps).rgb
                b = render(gt, cam, t=i / clip.fps).rgb
                ps.append(psnr(a, b))
                ss.append(ssim(a, b))
            novel[f"{yaw:+.0f}"] = {"psnr": float(np.mean(ps)), "ssim": float(np.mean(ss))}
        report["novel"] = novel
    if "semantic" in scene.decoders and scene.gaussians.features is not None:
        report["semantic"] = semantic_precision_recall(scene)
    if seconds is not None:
        report["seconds"] = float(seconds)
    return report


def format_report(report: dict) -> str:
    """A plain-text table of a quality report."""
    lines = [f"input views   PSNR {report['input']['psnr']:6.2f} dB   SSIM {report['input']['ssim']:.4f}   "
             f"({report['input']['frames']} frames, {report['gaussians']} Gaussians)"]
    for yaw, r in report.get("novel", {}).items():
        lines.append(f"novel {yaw:>4s} deg PSNR {r['psnr']:6.2f} dB   SSIM {r['ssim']:.4f}")
    for name, v in report["instance_iou"].items():
        lines.append(f"instance IoU  {name:12s} {v:.3f}")
    for name, v in report.get("semantic", {}).items():
        lines.append(f"semantic      {name:12s} precision {v['precision']:.3f} recall {v['recall']:.3f}")
    if "seconds" in report:
        lines.append(f"time          {report['seconds']:.1f} s")
    return "\n".join(lines)
