"""sha256 of every file the demo and the README's example commands write, to compare runs.

A refactoring that claims "behaviour unchanged" runs this before and after and
compares: every output must be byte-identical for the same seeds.

Usage::

    python3 -m benchmarks.digests OUT                 # run with ./src, write OUT/digests.json
    python3 -m benchmarks.digests OUT --src OLD/src   # the same with another source tree
    python3 -m benchmarks.digests --compare A.json B.json

Commands run on a generated plan (``map2map plan --seed 3``), a small HouseExpo
JSON and a DXF drawing in millimetres that this script writes, with fixed seeds.
A few fields are measured wall-clock times and differ between any two runs; they
are blanked before hashing and listed in the output (``VOLATILE``), nothing else is:
JSON keys ``wall_seconds``, ``seconds``, ``timings_s``; the ``seconds`` column of
``pairs.csv``; the creation/update dates and GUIDs ezdxf writes into a DXF header.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shlex
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: What is blanked before hashing, and why: measured times and ezdxf's header stamps.
VOLATILE = {
    ".json": "keys wall_seconds, seconds, timings_s, epoch_s, img_per_s, images_per_s, "
    "pairs_per_hour (measured times and rates)",
    "pairs.csv": "column seconds (measured time)",
    "log.csv": "columns epoch_s, img_per_s (a training log's measured times)",
    "paths": "the run's own work folder in JSON files and stdout, the source tree in stdout",
    ".html": "the report footer's 'Written <date> UTC'",
    "containers": ".npz, .safetensors, .sqlite and .skops are hashed by content (arrays, "
    "tensors and JSON header, table rows with worker and finish times blanked, zip members "
    "without their timestamps)",
    ".dxf": "header $TDCREATE $TDUCREATE $TDUPDATE $TDUUPDATE $TDINDWG $TDUSRTIMER "
    "$FINGERPRINTGUID $VERSIONGUID and the '<version> @ <date>' XRECORD (ezdxf stamps); "
    "commands run with PYTHONHASHSEED=0 "
    "(ezdxf orders the CLASSES section by a set)",
}
_JSON_TIMES = {"wall_seconds", "seconds", "timings_s", "epoch_s", "img_per_s", "images_per_s",
               "pairs_per_hour"}
_CSV_TIMES = {"pairs.csv": {"seconds"}, "log.csv": {"epoch_s", "img_per_s"}}
_DXF_STAMPS = {
    "$TDCREATE", "$TDUCREATE", "$TDUPDATE", "$TDUUPDATE", "$TDINDWG", "$TDUSRTIMER",
    "$FINGERPRINTGUID", "$VERSIONGUID",
}  # fmt: skip

# a small HouseExpo plan: two rooms split by a thin wall with a door gap (metres)
HOUSE = {
    "id": "digest_house",
    "room_num": 2,
    "bbox": {"min": [0.0, 0.0], "max": [6.0, 4.0]},
    "verts": [
        [0.0, 0.0], [3.0, 0.0], [3.0, 1.5], [3.04, 1.5], [3.04, 0.0], [6.0, 0.0],
        [6.0, 4.0], [3.04, 4.0], [3.04, 2.4], [3.0, 2.4], [3.0, 4.0], [0.0, 4.0],
    ],
    "room_category": {"Bedroom": [[0.0, 0.0, 3.0, 4.0]], "Kitchen": [[3.04, 0.0, 6.0, 4.0]]},
}  # fmt: skip

# world points (m) of the seed-3 apartment: room centres and a door
START, GOAL = (3.775, 1.775), (5.05, 4.35)
WAYPOINTS = [(3.775, 1.775), (6.25, 2.6), (6.25, 3.9), (5.05, 4.35)]


def _write_inputs(d: Path) -> None:
    import ezdxf

    d.mkdir(parents=True, exist_ok=True)
    (d / "house.json").write_text(json.dumps(HOUSE))
    (d / "wp.txt").write_text("".join(f"{x} {y}\n" for x, y in WAYPOINTS))
    (d / "pts.csv").write_text("x,y\n10,20\n50.5,60\n100,30\n")
    doc = ezdxf.new(units=4)  # millimetres
    msp = doc.modelspace()
    doc.layers.add("WALLS")
    doc.layers.add("FURNITURE")
    for a, b in [((0, 0), (6000, 0)), ((6000, 0), (6000, 4000)), ((6000, 4000), (0, 4000)),
                 ((0, 4000), (0, 0)), ((3000, 0), (3000, 1500)), ((3000, 2400), (3000, 4000))]:
        msp.add_line(a, b, dxfattribs={"layer": "WALLS"})  # fmt: skip
    msp.add_circle((1000, 1000), 300, dxfattribs={"layer": "FURNITURE"})
    doc.saveas(d / "plan_mm.dxf")


def commands(w: Path) -> list[list[str]]:
    """The README's example commands, on this script's inputs (relative to ``w``)."""
    (sx, sy), (gx, gy) = START, GOAL
    lines = f"""
    plan --seed 3 --out in/plan.yaml --figure in/plan_fig.png --meta in/plan_meta.json
    plan --seed 7 --kind office --size 30 20 --out office.yaml --figure office.png
    plan --seed 5 --furniture --out furnished.png
    convert in/house.json house.yaml --resolution 0.05
    convert in/plan_mm.dxf plan_dxf.yaml --layers WALLS --units mm --wall-thickness 0.1
    convert in/plan.yaml walls.dxf
    convert in/plan.yaml plan.png
    prep house.yaml house_256.png --size 256 --thicken 2 --crop --figure prep_fig.png
    show in/plan.yaml --out map.png
    show in/house.json --out house_show.png
    deform in/plan.yaml --out maps --samples 3 --seed 0 --quiet
    deform in/plan.yaml --out m_sg --start {sx} {sy} --goal {gx} {gy} --quiet
    deform in/plan.yaml --out m_wp --waypoints in/wp.txt --method ekf --fov 180 --quiet
    deform in/plan.yaml --out m_rep --seed 1 --trajectory maps/sample_001/trajectory.csv \
        --params maps/sample_001/params.yaml --quiet
    deform in/house.json --out m_house --seed 2 --quiet
    simulate in/plan.yaml --out run --seed 3 --duration 90 --quiet
    simulate in/house.json --out run_json --fov 180 --obstacles 2 --people 1 --gif \
        --duration 40 --quiet
    simulate in/plan.yaml --out run_wp --waypoints in/wp.txt --start {sx} {sy} 0.0 \
        --mapper oracle --quiet
    slam run --out slam_out --quiet
    slam run/run.log --out exp2 --backend graph --max-range 5 --quiet
    align run/slam_map.yaml in/plan.yaml --out al
    align run/slam_map.pgm plan.png --out al_pts --points in/pts.csv
    evaluate run/slam_map.yaml in/plan.yaml --out ev --quiet
    evaluate run/slam_map.pgm plan.png --out ev_png --resolution 0.05 --quiet
    evaluate --pairs in/pairs.csv --out batch --quiet
    autocorrect run/slam_map.yaml --out ac.yaml --dxf ac.dxf --figure ac.png
    synthesize in/plan.yaml --out syn --samples 2 --seed 0
    dataset build --out ds --plans generated --count 8 --seed 0 --source deform --size 64 --quiet
    dataset clean ds
    dataset export ds --format packed
    train ba --data ds --out tb --epochs 2 --device cpu --batch 4 --quiet
    train ab --data ds --out ta --schedule 32:1,64:1 --device cpu --batch 4 --quiet
    autocorrect in/plan.yaml --out ac_tb.yaml --model tb
    synthesize in/plan.yaml --out syn_ta --samples 1 --seed 0 --model ta
    deform in/plan.yaml --out bad --start 1 1
    slam in/wp.txt --out bad2
    """  # the last two: bad input, one line and exit 2
    return [shlex.split(c) for c in lines.replace("\\\n", " ").strip().splitlines()]


def run_all(out: Path, src: Path, demo: bool = True) -> dict:
    """Run the demo and every command with ``src`` first on the path; digest every file."""
    # ezdxf orders a DXF's CLASSES section by a set: fixed hash seed, fixed order
    env = dict(os.environ, PYTHONPATH=str(src), MPLBACKEND="Agg", PYTHONHASHSEED="0")
    work = out / "work"
    if work.exists():
        raise SystemExit(f"{work} exists; use a fresh OUT")
    _write_inputs(work / "in")
    log: dict[str, dict] = {}
    if demo:
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, "-m", "map2map", "demo", "--out", str(out / "demo"),
                            "--quiet"], env=env, capture_output=True, text=True)  # fmt: skip
        log["demo"] = {"rc": p.returncode, "seconds": round(time.perf_counter() - t0, 1)}
        print(f"demo: exit {p.returncode}, {log['demo']['seconds']} s", flush=True)
        if p.returncode:
            print(p.stderr[-3000:])
    for cmd in commands(work):
        if cmd[:2] == ["evaluate", "--pairs"]:
            (work / "in" / "pairs.csv").write_text(
                "slam,plan\n../run/slam_map.yaml,plan.yaml\n../run_wp/slam_map.yaml,plan.yaml\n"
            )
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, "-m", "map2map", *cmd], cwd=work, env=env,
                           capture_output=True, text=True)  # fmt: skip
        key = " ".join(cmd)
        stdout = p.stdout.replace(str(src), "<src>").replace(str(work), "<work>")
        stdout = re.sub(r"\d+\.\d+ s\b", "<s>", stdout)  # printed times
        stdout = _rates(stdout)
        stdout = re.sub(r"in \d+\.\d s:", "in <s>:", stdout)
        log[key] = {
            "rc": p.returncode,
            "seconds": round(time.perf_counter() - t0, 1),
            "stdout": hashlib.sha256(stdout.encode()).hexdigest()[:16],
            "stderr_last": _rates(p.stderr.strip().splitlines()[-1]) if p.stderr.strip() else "",
        }
        print(f"{p.returncode} {log[key]['seconds']:6.1f} s  map2map {key}", flush=True)
        if p.returncode not in (0, 2):
            print(p.stderr[-3000:])
    files = {}
    inputs = {"house.json", "wp.txt", "pts.csv", "plan_mm.dxf", "pairs.csv"}  # this script's
    for path in sorted(out.rglob("*")):
        if path.parent == work / "in" and path.name in inputs:
            continue
        if path.is_file() and path.name != "digests.json":
            files[str(path.relative_to(out))] = digest(path, {str(work): "<work>",
                                                               str(src): "<src>"})
    doc = {"src": str(src), "commands": log, "files": files, "volatile": VOLATILE}
    (out / "digests.json").write_text(json.dumps(doc, indent=1) + "\n")
    print(f"{len(files)} files digested -> {out / 'digests.json'}")
    return doc


def _rates(text: str) -> str:
    """Printed rates and durations blanked: "12 img/s", "(11123 pairs/h)", "in 3 s",
    tqdm's "[00:01<00:00, 2897.48pair/s]"."""
    text = re.sub(r"\d+(\.\d+)? ?(img/s|pairs?/h|pair/s|it/s|maps/s)", "<rate>", text)
    text = re.sub(r"\[\d\d:\d\d<\d\d:\d\d, [^\]]*\]", "[<t>]", text)
    return re.sub(r"\bin \d+ s\b", "in <t> s", text)


def _strip_times(o):
    if isinstance(o, dict):
        return {k: ("<t>" if k in _JSON_TIMES else _strip_times(v)) for k, v in o.items()}
    if isinstance(o, list):
        return [_strip_times(v) for v in o]
    return o


def _subst(text: str, paths: dict[str, str]) -> str:
    for k, v in paths.items():
        text = text.replace(k, v)
    return text


def _json_canon(text: str, paths: dict[str, str]) -> bytes:
    try:
        o = json.loads(_subst(text, paths))
    except ValueError:
        return _subst(text, paths).encode()
    return json.dumps(_strip_times(o), sort_keys=True).encode()


def _npz(path: Path, paths: dict[str, str]) -> str:
    """Every array's bytes; string arrays (a packed dataset's JSON meta) canonicalised."""
    import numpy as np

    h = hashlib.sha256()
    with np.load(path, allow_pickle=False) as z:
        for k in sorted(z.files):
            a = z[k]
            h.update(k.encode())
            if a.dtype.kind == "U":
                for item in a.ravel().tolist():
                    h.update(_json_canon(item, paths))
            else:
                h.update(str(a.dtype).encode() + str(a.shape).encode() + a.tobytes())
    return h.hexdigest()


def _safetensors(path: Path, paths: dict[str, str]) -> str:
    """The tensors' bytes and the JSON header (paths replaced, measured times blanked)."""
    import struct

    data = path.read_bytes()
    n = struct.unpack("<Q", data[:8])[0]
    head = json.loads(data[8:8 + n])
    meta = head.pop("__metadata__", {})
    h = hashlib.sha256()
    h.update(json.dumps({k: _json_canon(v, paths).decode() for k, v in meta.items()},
                        sort_keys=True).encode())
    h.update(json.dumps(head, sort_keys=True).encode())
    h.update(data[8 + n:])
    return h.hexdigest()


def _sqlite(path: Path, paths: dict[str, str]) -> str:
    """Every table's rows in key order, times blanked (a dataset's manifest)."""
    import sqlite3

    con = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    h = hashlib.sha256()
    try:
        tables = [r[0] for r in con.execute(
            "select name from sqlite_master where type='table' order by name")]
        for t in tables:
            cols = [r[1] for r in con.execute(f"pragma table_info({t})")]
            for row in con.execute(f"select * from {t} order by 1"):
                vals = []
                for c, v in zip(cols, row, strict=True):
                    if c in _JSON_TIMES or c in ("finished", "worker"):
                        v = "<t>"
                    elif isinstance(v, str):
                        v = _json_canon(v, paths).decode()
                    vals.append(repr(v))
                h.update(f"{t}:{','.join(vals)}\n".encode())
    finally:
        con.close()
    return h.hexdigest()


def _zip(path: Path, paths: dict[str, str]) -> str:
    """The members' contents, not their timestamps or names (a saved skops model names its
    arrays by object id): the sorted member hashes and the schema with ids blanked."""
    import zipfile

    parts = []
    with zipfile.ZipFile(path) as z:
        for name in z.namelist():
            data = z.read(name)
            if name.endswith(".json"):
                data = re.sub(rb"\d{9,}", b"<id>", data)
            parts.append(hashlib.sha256(data).hexdigest())
    return hashlib.sha256("".join(sorted(parts)).encode()).hexdigest()


_CONTAINERS = {".npz": _npz, ".safetensors": _safetensors, ".sqlite": _sqlite,
               ".skops": _zip}


def digest(path: Path, paths: dict[str, str] | None = None) -> str:
    """sha256 of a file, with the fields listed in :data:`VOLATILE` blanked.

    ``paths`` maps absolute folder names (the run's work folder) to placeholders in
    JSON files, which record where their inputs were read."""
    data = path.read_bytes()
    if path.suffix in _CONTAINERS:
        return _CONTAINERS[path.suffix](path, paths or {})
    if path.suffix == ".html":
        data = re.sub(rb"Written \d{4}-\d\d-\d\d \d\d:\d\d UTC", b"Written <date>", data)
    if path.suffix == ".json":
        for k, v in (paths or {}).items():
            data = data.replace(k.encode(), v.encode())
        try:
            data = json.dumps(_strip_times(json.loads(data)), sort_keys=True).encode()
        except ValueError:
            pass
    elif path.name in _CSV_TIMES:
        lines = data.decode().splitlines()
        head = lines[0].split(",") if lines else []
        cols = {i for i, h in enumerate(head) if h in _CSV_TIMES[path.name]}
        data = "\n".join(
            ",".join("<t>" if i in cols else c for i, c in enumerate(line.split(",")))
            for line in lines
        ).encode()
    elif path.suffix == ".dxf":
        lines = data.decode(errors="replace").splitlines()
        keep, skip = [], 0
        for line in lines:
            if skip:
                skip -= 1
                keep.append("<stamp>")
                continue
            keep.append(line)
            if line.strip() in _DXF_STAMPS:
                skip = 2  # group code and value
        # ezdxf also stamps its version and the write time into an XRECORD
        text = re.sub(r"@ \d{4}-\d\d-\d\dT[\d:.+]+", "@ <date>", "\n".join(keep))
        data = text.encode()
    return hashlib.sha256(data).hexdigest()


def compare(a: Path, b: Path) -> int:
    """Print every file and command that differs; exit 1 if any does."""
    da, db = json.loads(a.read_text()), json.loads(b.read_text())
    skip = {f"work/in/{n}" for n in ("house.json", "wp.txt", "pts.csv", "plan_mm.dxf", "pairs.csv")}
    fa = {k: v for k, v in da["files"].items() if k not in skip}
    fb = {k: v for k, v in db["files"].items() if k not in skip}
    bad = 0
    for k in sorted(set(fa) | set(fb)):
        if fa.get(k) != fb.get(k):
            bad += 1
            what = "only in A" if k not in fb else "only in B" if k not in fa else "differs"
            print(f"{what:<10s} {k}")
    ca, cb = da["commands"], db["commands"]
    for k in sorted(set(ca) | set(cb)):
        x, y = ca.get(k, {}), cb.get(k, {})
        for f in ("rc", "stdout", "stderr_last"):
            if x.get(f) != y.get(f):
                bad += 1
                print(f"command {f} differs: map2map {k}\n   A: {x.get(f)!r}\n   B: {y.get(f)!r}")
    same = len(set(fa) & set(fb)) - sum(1 for k in set(fa) & set(fb) if fa[k] != fb[k])
    print(f"{same} files identical, {bad} differences ({len(fa)} vs {len(fb)} files)")
    return 1 if bad else 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", nargs="?", type=Path, help="output folder (fresh)")
    ap.add_argument("--src", type=Path, default=HERE.parent / "src", help="source tree to run")
    ap.add_argument("--no-demo", action="store_true", help="only the README commands")
    ap.add_argument("--compare", nargs=2, type=Path, metavar=("A", "B"))
    args = ap.parse_args(argv)
    if args.compare:
        return compare(*args.compare)
    if args.out is None:
        ap.error("give OUT or --compare A B")
    run_all(args.out, args.src.resolve(), demo=not args.no_demo)
    return 0


if __name__ == "__main__":
    sys.exit(main())
