"""`AssetRecord`: what the index knows about one asset, without loading it."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

__all__ = ["ASSET_KINDS", "UP_AXES", "AssetRecord"]

ASSET_KINDS = ("mesh", "splat", "sky")   # a surface mesh, a 3DGS .ply, an HDR panorama
UP_AXES = ("z", "y", "-y")               # the axis that points up in the file's own frame


@dataclass(frozen=True)
class AssetRecord:
    """One asset of a source.

    Attributes:
        id: unique, stable id, "<source>/<collection>/<slug>" (e.g. "sweethome3d/blendswap-cc-0/armchair").
        name: human name ("Armchair").
        category: the source's category ("Living room"), or a best guess ("object").
        tags: extra words for search ("sofa", "seat").
        source: the source's name ("sweethome3d", "robosuite", "folder", "studiolights").
        licence: the licence text of the asset's collection.
        kind: "mesh", "splat" or "sky".
        path: the file on disk (a catalogue zip when `member` is set).
        member: the file's name inside the zip at `path`, or None for a plain file.
        up_axis: the file's up axis, one of `UP_AXES`.
        unit_scale: metres per file unit.
        size_m: real-world extents (x, y, z) in metres in the z-up world frame, or None when only
            the file knows (its native extents times `unit_scale`).
        model_rotation: a row-major 3x3 rotation applied in the file's frame before anything else
            (Sweet Home 3D's `modelRotation`), or None.
        creator: who made it, when the source says.
    """

    id: str
    name: str
    category: str
    source: str
    licence: str
    kind: str
    path: str
    member: str | None = None
    tags: tuple[str, ...] = ()
    up_axis: str = "z"
    unit_scale: float = 1.0
    size_m: tuple[float, float, float] | None = None
    model_rotation: tuple[float, ...] | None = None
    creator: str = ""
    extra: dict[str, Any] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if self.kind not in ASSET_KINDS:
            raise ValueError(f"Expected kind in {ASSET_KINDS}, found {self.kind!r} for asset {self.id!r}")
        if self.up_axis not in UP_AXES:
            raise ValueError(f"Expected up_axis in {UP_AXES}, found {self.up_axis!r} for asset {self.id!r}")
        if not self.unit_scale > 0:
            raise ValueError(f"Expected unit_scale > 0, found {self.unit_scale!r} for asset {self.id!r}")
        if self.size_m is not None and (len(self.size_m) != 3 or min(self.size_m) <= 0):
            raise ValueError(f"Expected size_m as 3 positive numbers, found {self.size_m!r} for asset {self.id!r}")
        if self.model_rotation is not None and len(self.model_rotation) != 9:
            raise ValueError(f"Expected model_rotation as 9 numbers, found {len(self.model_rotation)} "
                             f"for asset {self.id!r}")

    @property
    def file_label(self) -> str:
        """The file, as people read it in messages: "archive.sh3f!folder/model.obj" or "model.obj"."""
        return f"{self.path}!{self.member}" if self.member else self.path

    @property
    def search_text(self) -> str:
        """Name, category and tags in one phrase (what search and embeddings read)."""
        return ", ".join([self.name, self.category, *self.tags])

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (tuples become lists)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> AssetRecord:
        """The inverse of `to_dict`."""
        d = dict(d)
        d["tags"] = tuple(d.get("tags") or ())
        for key in ("size_m", "model_rotation"):
            if d.get(key) is not None:
                d[key] = tuple(float(x) for x in d[key])
        return cls(**d)
