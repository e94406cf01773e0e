"""Reading an asset's files: the main file (plain, or a member of a catalogue zip) and the files
it refers to (MTL materials, textures), with a size limit and a texture check.

`AssetFiles.resolver()` gives trimesh a resolver that finds referenced files next to the main
file, by their written path (which may climb out of the folder, as robosuite's do) or else by
their base name (catalogues often keep an author's absolute Windows path), and that warns,
naming the file, when a texture is missing or unreadable (the material's colour is used then).
"""

from __future__ import annotations

import hashlib
import io
import os
import posixpath
import re
import warnings
import zipfile
from pathlib import Path

import trimesh

from .ac3d import find_texture, texture_names
from .errors import AssetError, AssetWarning
from .record import AssetRecord

__all__ = ["IMAGE_SUFFIXES", "MAX_FILE_BYTES", "AssetFiles"]

MAX_FILE_BYTES = 64 * 1024 * 1024
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".gif", ".tif", ".tiff")
_DIFFUSE = re.compile(r"^\s*map_Kd\s+(?:-\S+\s+\S+\s+)*(.+?)\s*$", re.MULTILINE | re.IGNORECASE)
_REFERENCE = re.compile(r"^\s*(?:mtllib|map_Kd|map_Ka|map_d|map_bump|bump)\s+(?:-\S+\s+\S+\s+)*(.+?)\s*$",
                        re.MULTILINE | re.IGNORECASE)


class AssetFiles:
    """The files of one asset: `main()` bytes, `read(name)` of a referenced file, `content_hash()`.

    Args:
        record: the asset.
        max_bytes: refuse a main file larger than this (`AssetError`).
    """

    def __init__(self, record: AssetRecord, max_bytes: int = MAX_FILE_BYTES) -> None:
        self.record, self.max_bytes = record, max_bytes
        self._zip: zipfile.ZipFile | None = None
        self._main: bytes | None = None
        self._diffuse: set[str] | None = None
        self.warned: set[str] = set()

    # ------------------------------------------------------------ the main file
    @property
    def label(self) -> str:
        return self.record.file_label

    @property
    def folder(self) -> str:
        """The main file's folder (inside the zip for catalogue members)."""
        if self.record.member:
            return posixpath.dirname(self.record.member)
        return str(Path(self.record.path).parent)

    def _archive(self) -> zipfile.ZipFile:
        if self._zip is None:
            try:
                self._zip = zipfile.ZipFile(self.record.path)
            except (OSError, zipfile.BadZipFile) as exc:
                raise AssetError(f"Cannot open the catalogue {self.record.path}: {exc}") from None
        return self._zip

    def size(self) -> int:
        """Bytes of the main file (`AssetError` when it is missing)."""
        try:
            if self.record.member:
                return self._archive().getinfo(self.record.member).file_size
            return os.stat(self.record.path).st_size
        except (KeyError, OSError) as exc:
            raise AssetError(f"Missing asset file {self.label} ({type(exc).__name__}: {exc})") from None

    def main(self) -> bytes:
        """The main file's bytes, after the size check (read once)."""
        if self._main is None:
            size = self.size()
            if size > self.max_bytes:
                raise AssetError(f"Refusing {self.label}: {size / 2**20:.1f} MiB is above the "
                                 f"{self.max_bytes / 2**20:.0f} MiB limit for one asset file")
            self._main = self._read_exact(self.record.member or self.record.path)
        return self._main

    def _read_exact(self, name: str) -> bytes:
        try:
            if self.record.member:
                return self._archive().read(name)
            with open(name, "rb") as f:
                return f.read()
        except (KeyError, OSError, zipfile.BadZipFile, EOFError) as exc:
            raise AssetError(f"Cannot read {self.record.path}{'!' + name if self.record.member else ''}: "
                             f"{type(exc).__name__}: {exc}") from None

    # ------------------------------------------------------- referenced files
    def _candidates(self, name: str, folder: str) -> list[str]:
        name = name.strip().strip('"').replace("\\", "/")
        base = posixpath.basename(name)
        if self.record.member:
            return [posixpath.normpath(posixpath.join(folder, name)), posixpath.join(folder, base)]
        return [os.path.normpath(os.path.join(folder, name)), os.path.join(folder, base)]

    def read(self, name: str, folder: str | None = None) -> bytes:
        """A file the main file refers to, by its written path or else its base name (`KeyError`)."""
        folder = self.folder if folder is None else folder
        for candidate in self._candidates(name, folder):
            try:
                return self._read_exact(candidate)
            except AssetError:
                continue
        raise KeyError(name)

    def references(self, data: bytes, folder: str | None = None) -> list[tuple[str, bytes]]:
        """(name, bytes) of every MTL and texture the OBJ text `data` refers to, recursively (once each)."""
        out: list[tuple[str, bytes]] = []
        seen: set[str] = set()
        stack = [data]
        while stack:
            text = stack.pop().decode("latin-1")
            for ref in _REFERENCE.findall(text):
                if ref in seen:
                    continue
                seen.add(ref)
                try:
                    blob = self.read(ref, folder)
                except KeyError:
                    continue
                out.append((ref, blob))
                if ref.lower().endswith(".mtl"):
                    stack.append(blob)
        return out

    def diffuse_textures(self) -> set[str]:
        """The names of the colour textures (`map_Kd`) of the OBJ's materials (computed once)."""
        if self._diffuse is None:
            self._diffuse = set()
            if (self.record.member or self.record.path).lower().endswith(".obj"):
                for name, blob in self.references(self.main()):
                    if name.lower().endswith(".mtl"):
                        self._diffuse |= set(_DIFFUSE.findall(blob.decode("latin-1")))
        return self._diffuse

    def texture_member(self) -> bytes | None:
        """The bytes of the colour texture the record names (`extra["texture"]`, a path next to a
        plain file or a member of the same zip), or None when it names none.

        Raises:
            AssetError: the named texture is missing or unreadable.
        """
        name = self.record.extra.get("texture")
        if not name:
            return None
        if not self.record.member:
            name = os.path.join(self.folder, name)
        return self._read_exact(name)

    def ac3d_texture(self, name: str) -> bytes | None:
        """The bytes of a texture an AC3D file names, or None when it is not found: in a zip, next to
        the file (by written path or base name); on disk, where `ac3d.find_texture` finds it."""
        if self.record.member:
            try:
                return self.read(name)
            except KeyError:
                return None
        path = find_texture(self.folder, name)
        return None if path is None else self._read_exact(str(path))

    def content_hash(self) -> str:
        """sha256 over the main file and every file it refers to (the conversion cache's key part)."""
        main = self.main()
        h = hashlib.sha256(main)
        label = (self.record.member or self.record.path).lower()
        if label.endswith(".obj"):
            for name, blob in sorted(self.references(main)):
                h.update(name.encode())
                h.update(hashlib.sha256(blob).digest())
        if label.endswith(".ac"):
            for name in texture_names(main):
                blob = self.ac3d_texture(name)
                h.update(name.encode())
                h.update(hashlib.sha256(blob or b"").digest())
        texture = self.texture_member()
        if texture is not None:
            h.update(str(self.record.extra["texture"]).encode())
            h.update(hashlib.sha256(texture).digest())
        return h.hexdigest()

    def resolver(self) -> _AssetResolver:
        return _AssetResolver(self, self.folder)

    def warn_texture(self, name: str, reason: str) -> None:
        """Warn once per colour texture that it is not used (bump and normal maps are never used)."""
        if name not in self.warned and name in self.diffuse_textures():
            self.warned.add(name)
            warnings.warn(AssetWarning(f"Texture {name!r} of {self.label} {reason}; using the material colour"),
                          stacklevel=4)

    def close(self) -> None:
        self._main = None
        if self._zip is not None:
            self._zip.close()
            self._zip = None


class _AssetResolver(trimesh.resolvers.Resolver):
    """trimesh resolver over `AssetFiles`, checking textures before trimesh sees them."""

    def __init__(self, files: AssetFiles, folder: str) -> None:
        self.files, self.folder = files, folder

    def get(self, name: str) -> bytes:
        try:
            blob = self.files.read(name, self.folder)
        except KeyError:
            if name.lower().endswith(IMAGE_SUFFIXES):
                self.files.warn_texture(name, "is missing")
            raise
        if name.lower().endswith(IMAGE_SUFFIXES):
            from PIL import Image

            try:
                with Image.open(io.BytesIO(blob)) as im:
                    im.load()
            except Exception as exc:  # noqa: BLE001 - PIL raises many types for a bad image
                self.files.warn_texture(name, f"is unreadable ({type(exc).__name__}: {exc})")
                raise KeyError(name) from None
        return blob

    def namespaced(self, namespace: str) -> _AssetResolver:
        joiner = posixpath.join if self.files.record.member else os.path.join
        return _AssetResolver(self.files, joiner(self.folder, namespace))

    def write(self, name: str, data: bytes) -> None:
        raise AssetError("Asset files are read-only")

    def keys(self):
        return iter(())
