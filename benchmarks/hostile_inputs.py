"""Re-run the hostile-input and damaged-file attacks of issue #22 (items 4, 5, 7, 8) and tabulate them.

    .venv/bin/python benchmarks/hostile_inputs.py            # this checkout
    PYTHONPATH=/path/to/old/tree .venv/bin/python benchmarks/hostile_inputs.py   # an older tree, to compare

Only the public API is used, so the same script runs on the code before the fix. Each attack that
could exhaust the machine runs in a child process under a 3 GiB address-space limit and a timeout.
Columns: inputs tried, clean errors (a ValueError subclass that names the file, where there is
one), correct results (identical load, exact values), bad outcomes (a silent change, a raw
exception, an error without the file, memory or time blown).
"""

from __future__ import annotations

import contextlib
import copy
import glob
import hashlib
import io
import json
import os
import resource
import struct
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
TMP = Path(tempfile.mkdtemp(prefix="hostile_"))
GUARD_BYTES = 3 << 30
GUARD_SECONDS = 60


def _row(name, tried, clean, correct, bad, note=""):
    return {"attack": name, "inputs": tried, "clean errors": clean, "correct": correct, "bad outcomes": bad,
            "note": note}


# ----------------------------------------------------------------- files
def _tiny_clip():
    import morphosim_gym as ms
    from tests.conftest import make_tiny_scene

    s = make_tiny_scene(n_per_object=8, frames=3)
    rng = np.random.default_rng(1)
    return ms.GeneratedClip(frames=rng.integers(0, 255, (3, 16, 16, 3), dtype=np.uint8),
                            cameras=[s.camera.resized(16, 16)] * 3, fps=4.0,
                            depth=rng.uniform(1, 5, (3, 16, 16)).astype(np.float32),
                            masks=rng.integers(-1, 3, (3, 16, 16)).astype(np.int32),
                            labels={0: "ground", 1: "ball", 2: "cube"}, prompt="a ball", ground_truth=s,
                            info={"seed": 3})


def _fingerprint_scene(s):
    out = []
    while s is not None:
        out.append((s.content_hash(), json.dumps(s.metadata(), sort_keys=True, default=str)))
        s = s.parent
    return out


def _fingerprint_clip(c):
    return (c.content_hash(), c.prompt, json.dumps(c.info, sort_keys=True), _fingerprint_scene(c.ground_truth))


def _mutations(raw: bytes, rng, header_end: int, count: int):
    for i in range(count):
        b = bytearray(raw)
        kind = i % 4
        if kind in (0, 1):                      # a bit flip in the header, or anywhere
            pos = int(rng.integers(0, header_end if kind == 0 else len(raw)))
            b[pos] ^= 1 << int(rng.integers(0, 8))
        elif kind == 2:                         # truncation
            b = b[: int(rng.integers(0, len(raw)))]
        else:                                   # a duplicated run of bytes
            start = int(rng.integers(0, len(raw)))
            b[start:start] = raw[start:start + int(rng.integers(1, 65))]
        yield bytes(b)


def attack_file_fuzz(n: int = 300) -> list[dict]:
    import morphosim_gym as ms
    from tests.conftest import make_tiny_scene

    s = make_tiny_scene(n_per_object=8, frames=3)
    scene = s.derive("grey", gaussians=s.gaussians.replace(colors=np.full_like(s.gaussians.colors, 0.5)))
    rows = []
    for what, obj, save, load, fp in (("scene", scene, ms.save_scene, ms.load_scene, _fingerprint_scene),
                                      ("clip", _tiny_clip(), ms.save_clip, ms.load_clip, _fingerprint_clip)):
        path = TMP / f"x.{what}"
        save(obj, path)
        raw = path.read_bytes()
        header_end = 24 + struct.unpack_from("<Q", raw, 16)[0]
        want = fp(obj)
        clean = correct = silent = raw_exc = unnamed = 0
        damaged = TMP / f"d.{what}"
        for b in _mutations(raw, np.random.default_rng(22), header_end, n):
            damaged.write_bytes(b)
            try:
                got = fp(load(damaged))
            except ms.SceneFileError as exc:
                if str(damaged) in str(exc):
                    clean += 1
                else:
                    unnamed += 1
                continue
            except Exception:                   # noqa: BLE001 - counting what escapes
                raw_exc += 1
                continue
            if got == want:
                correct += 1
            else:
                silent += 1
        rows.append(_row(f"{what} file: {n} bit flips / truncations / duplicated runs", n, clean, correct,
                         silent + raw_exc + unnamed,
                         f"silent changes {silent}, raw exceptions {raw_exc}, errors without the file {unnamed}"))
    return rows


def attack_info_cli(n: int = 100) -> list[dict]:
    """`morphosim info` on damaged files: exit status and no traceback."""
    import morphosim_gym as ms
    from morphosim_gym.cli import main

    path = TMP / "i.msim"
    ms.save_clip(_tiny_clip(), path)
    raw = path.read_bytes()
    header_end = 24 + struct.unpack_from("<Q", raw, 16)[0]
    clean = ok = bad = 0
    damaged = TMP / "di.msim"
    for b in _mutations(raw, np.random.default_rng(7), header_end, n):
        damaged.write_bytes(b)
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                code = main(["info", str(damaged)])
        except BaseException:                   # noqa: BLE001 - a traceback for the user
            bad += 1
            continue
        if code == 0:
            ok += 1
        elif str(damaged) in err.getvalue():
            clean += 1
        else:
            bad += 1
    return [_row(f"morphosim info on {n} damaged clips", n, clean, ok, bad, "bad: a traceback or no file name")]


def _bomb_v1(path: Path, entries: int, blob_bytes: int) -> None:
    """A version-1 file whose table points `entries` arrays at one blob (both versions read v1)."""
    blob = bytes(blob_bytes)
    table = [{"name": f"x{i}", "dtype": "|u1", "shape": [blob_bytes], "offset": 0, "nbytes": blob_bytes}
             for i in range(entries)]
    header = json.dumps({"kind": "scene", "metadata": {"scenes": []}, "arrays": table, "data_nbytes": blob_bytes,
                         "data_sha256": hashlib.sha256(blob).hexdigest()}).encode()
    prefix = b"MORPHOSIM4D\0" + struct.pack("<IQ", 1, len(header)) + header
    path.write_bytes(prefix + b"\0" * ((-len(prefix)) % 64) + blob)


def one_bomb() -> None:
    import morphosim_gym as ms

    path = TMP / "bomb.msim"
    _bomb_v1(path, 200, 64 << 20)
    try:
        ms.load_scene(path)
    except ms.SceneFileError as exc:
        print("CLEAN" if str(path) in str(exc) else "UNNAMED")
        return
    print("LOADED")


# ---------------------------------------------------------------------- ply
def attack_ply() -> list[dict]:
    import morphosim_gym as ms

    rng = np.random.default_rng(0)
    props = ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
             "rot_0", "rot_1", "rot_2", "rot_3"]
    cols = rng.normal(size=(10, len(props))).astype(np.float32)
    cols[:, 7:10] = -3
    tried = clean = correct = bad = 0
    for fmt, order in (("binary_little_endian", "<"), ("binary_big_endian", ">"), ("ascii", "")):
        for before in ("", "element camera 1\nproperty double fx\n",
                       "element face 1\nproperty list uchar int vertex_indices\n"):
            head = f"ply\nformat {fmt} 1.0\n{before}element vertex 10\n"
            head += "".join(f"property float {p}\n" for p in props) + "end_header\n"
            if order:
                pre = b""
                if "camera" in before:
                    pre = np.array([500.0], order + "f8").tobytes()
                elif "face" in before:
                    pre = b"\x03" + np.array([0, 1, 2], order + "i4").tobytes()
                body = pre + cols.astype(order + "f4").tobytes()
            else:
                pre = "500.0\n" if "camera" in before else ("3 0 1 2\n" if "face" in before else "")
                body = (pre + "\n".join(" ".join(repr(float(v)) for v in r) for r in cols) + "\n").encode()
            path = TMP / "v.ply"
            path.write_bytes(head.encode() + body)
            tried += 1
            try:
                g = ms.read_ply(path)
            except ValueError:
                bad += 1                        # a valid file refused
                continue
            exact = np.allclose(g.means, cols[:, :3], atol=1e-6)
            correct += exact
            bad += not exact
    path = TMP / "m.ply"
    path.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nend_header\n"
                     + bytes(4))
    tried += 1
    try:
        ms.read_ply(path)
        bad += 1
    except ValueError as exc:
        clean += str(path) in str(exc) and "opacity" in str(exc)
        bad += not (str(path) in str(exc) and "opacity" in str(exc))
    return [_row("valid PLY layouts (3 formats x elements before vertex) + a missing field", tried, clean, correct,
                 bad, "bad: a misread, or a valid file refused")]


# -------------------------------------------------------------------- cache
def attack_cache() -> list[dict]:
    import morphosim_gym as ms

    rows = []
    gen = {"num_frames": 2, "width": 32, "height": 32}
    cache = TMP / "cache"
    sim = ms.MorphoSim(cache=True, cache_dir=str(cache), generation=dict(gen))
    prompt = "a red ball moves from left to right"
    want = sim.generate_clip(prompt, seed=1).content_hash()
    entry = next((cache / "clip").glob("*"))
    fails = ok = 0
    for damage in ("truncate", "rename"):
        raw = entry.read_bytes()
        entry.write_bytes(raw[:-100] if damage == "truncate" else raw.replace(b'"data_nbytes"', b'"data_nbytez"'))
        for _ in range(3):                      # the damaged call and two more
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    ok += sim.generate_clip(prompt, seed=1).content_hash() == want
            except Exception:                   # noqa: BLE001
                fails += 1
    rows.append(_row("cache: damaged clip entry (truncated, renamed header key), 3 calls each", 6, 0, ok, fails,
                     "bad: a call that fails on the damaged entry"))
    killer = ("import os, signal, sys, numpy as np\n"
              "import morphosim_gym as ms\n"
              "from tests.conftest import make_tiny_scene\n"
              "os.replace = lambda *a: os.kill(os.getpid(), signal.SIGKILL)\n"
              "ms.save_scene(make_tiny_scene(n_per_object=3000), sys.argv[1])\n")
    target = cache / "scene" / "k.msim"
    target.parent.mkdir(parents=True, exist_ok=True)
    for _ in range(8):
        subprocess.run([sys.executable, "-c", killer, str(target)], capture_output=True, env=dict(os.environ), check=False)
    temps = list(target.parent.glob(".*.tmp"))
    size = sum(p.stat().st_size for p in temps)
    for p in temps:                              # killed a while ago
        os.utime(p, (time.time() - 30, time.time() - 30))
    ms.MorphoSim(cache=True, cache_dir=str(cache), reconstruction="oracle",
                 generation=dict(gen)).generate(prompt, seed=9)
    left = list(target.parent.glob(".*.tmp"))
    rows.append(_row(f"cache: 8 killed writers ({size / 1e6:.1f} MB of temporaries), then one cache write",
                     len(temps), 0, len(temps) - len(left), len(left), "bad: temporaries left behind"))
    return rows


# --------------------------------------------------------------------- yaml
def _laughs(levels=9, width=9) -> str:
    """A suite whose description is the classic nested-alias list (str() of it is 9^9 words long)."""
    text = "  - &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n"
    for i in range(1, levels + 1):
        text += f"  - &l{i} [" + ", ".join([f"*l{i - 1}"] * width) + "]\n"
    return "name: s\nenv: MorphoSim/Track-v0\nperturbations: []\ndescription:\n" + text


def one_laughs() -> None:
    from morphosim_gym.bench.suite import load_suite

    path = TMP / "laughs.yaml"
    path.write_text(_laughs())
    start = time.perf_counter()
    try:
        load_suite(path)
        print("LOADED")
    except ValueError as exc:
        print("CLEAN" if str(path) in str(exc) else "UNNAMED", f"{time.perf_counter() - start:.3f}s")


def attack_yaml_types() -> list[dict]:
    import yaml
    from morphosim_gym.tasks import load_task_spec

    from morphosim_gym.bench.suite import load_suite

    wrong = [123, "abc", [1], {"k": 1}, None, True, 1e308, -1, [[1]], ""]

    def paths(d, pre=()):
        items = d.items() if isinstance(d, dict) else enumerate(d) if isinstance(d, list) else ()
        for k, v in items:
            yield pre + (k,)
            yield from paths(v, pre + (k,))

    tried = clean = loaded = bad = 0
    files = [(f, load_task_spec) for f in sorted(glob.glob(str(ROOT / "tasks" / "*.yaml")))]
    files += [(f, load_suite) for f in sorted(glob.glob(str(ROOT / "tasks" / "suites" / "*.yaml")))]
    path = TMP / "t.yaml"
    for f, loader in files:
        base = yaml.safe_load(Path(f).read_text())
        for p in paths(base):
            for w in wrong:
                d = copy.deepcopy(base)
                parent = d
                for k in p[:-1]:
                    parent = parent[k]
                parent[p[-1]] = w
                path.write_text(yaml.safe_dump(d))
                tried += 1
                try:
                    loader(str(path))
                    loaded += 1
                except ValueError as exc:
                    clean += str(path) in str(exc)
                    bad += str(path) not in str(exc)
                except Exception:               # noqa: BLE001
                    bad += 1
    rows = [_row("task/suite YAML: every value replaced by 10 wrong types", tried, clean, loaded, bad,
                 "correct = still loads (a lenient str() of a number, say); bad: TypeError or no file name")]
    dup = TMP / "dup.yaml"
    dup.write_text("name: s\nenv: MorphoSim/Track-v0\nperturbations: []\nepisodes: 3\nepisodes: 30\n")
    try:
        load_suite(dup)
        rows.append(_row("suite YAML with a duplicate key", 1, 0, 0, 1, "accepted silently"))
    except ValueError as exc:
        rows.append(_row("suite YAML with a duplicate key", 1, int(str(dup) in str(exc)), 0,
                         int(str(dup) not in str(exc))))
    return rows


# -------------------------------------------------------------------- sizes
def one_render() -> None:
    import morphosim_gym as ms
    from tests.conftest import make_tiny_scene

    s = make_tiny_scene(n_per_object=5)
    try:
        ms.render(s, ms.Camera.look_at((0, -4, 2), (0, 0.5, 0.3), 16384, 16384, 60))
        print("LOADED")
    except ValueError:
        print("CLEAN")


def attack_sizes() -> list[dict]:
    import morphosim_gym as ms
    from morphosim_gym.bench.suite import load_suite
    from morphosim_gym.generate.compose import GenerationConfig

    clean = bad = 0
    try:
        GenerationConfig(num_frames=1000, width=4096, height=4096)
        bad += 1
    except ValueError as exc:
        clean += "GiB" in str(exc)
        bad += "GiB" not in str(exc)
    try:
        load_suite("smoke").with_episodes(10**8)
        bad += 1
    except ValueError:
        clean += 1
    rows = [_row("sizes: 1000 x 4096² generation config, --episodes 10^8", 2, clean, 0, bad)]
    texts = ["a billion balls bounce", "two billion balls bounce", "countless balls bounce", "1e9 balls bounce",
             "a trillion cubes"]
    clean = bad = 0
    for t in texts:
        try:
            plan = ms.parse(t)
            bad += 1
            del plan
        except ms.CommandError:
            clean += 1
    rows.append(_row("parser: 'a billion balls' and 4 more unbounded counts", len(texts), clean, 0, bad,
                     "bad: parsed as a small count"))
    return rows


# ------------------------------------------------------------------- driver
def _guarded(name: str, label: str) -> dict:
    """Run `one_<name>` in a child under the memory limit and timeout."""
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (GUARD_BYTES, GUARD_BYTES))

    start = time.perf_counter()
    try:
        proc = subprocess.run([sys.executable, __file__, "--one", name], capture_output=True, text=True,
                              timeout=GUARD_SECONDS, preexec_fn=limit, env=dict(os.environ), check=False)
        out = proc.stdout.strip().splitlines()[-1:] or [f"exit {proc.returncode}: {proc.stderr.strip()[-120:]}"]
        result = out[0]
    except subprocess.TimeoutExpired:
        result = f"TIMEOUT after {GUARD_SECONDS}s"
    seconds = time.perf_counter() - start
    clean = result.startswith("CLEAN")
    return _row(label, 1, int(clean), 0, int(not clean), f"{result} ({seconds:.1f} s in a 3 GiB child)")


def main() -> None:
    if sys.argv[1:2] == ["--one"]:
        globals()[f"one_{sys.argv[2]}"]()
        return
    rows = []
    rows += attack_file_fuzz()
    rows += attack_info_cli()
    rows.append(_guarded("bomb", "65 MB .msim, 200 table entries at one blob (12.5 GB if copied per entry)"))
    rows += attack_ply()
    rows += attack_cache()
    rows.append(_guarded("laughs", "603-byte 'billion laughs' suite (9 x 9 nested aliases in its description)"))
    rows += attack_yaml_types()
    rows.append(_guarded("render", "16384² render"))
    rows += attack_sizes()
    keys = ["attack", "inputs", "clean errors", "correct", "bad outcomes", "note"]
    print("| " + " | ".join(keys) + " |\n|" + "---|" * len(keys))
    for r in rows:
        print("| " + " | ".join(str(r[k]) for k in keys) + " |")


if __name__ == "__main__":
    main()
