#!/usr/bin/env python3
"""Check a sweep's output folder with independent readers: pandas for the manifest, rosbags for
every bag, and that every recorded frame carries its telemetry.

usage: check_sweep.py OUT_DIR

Reads manifest.jsonl and manifest.csv with pandas (they must agree on index and status); for every
`ok` job opens its bag with rosbags, checks its size and sha256 against the manifest, and that
every /drape/mesh message has a diagnostic_msgs/msg/DiagnosticArray on /diagnostics at the same
log time with the quality keys. Prints JSON on stdout:
  {"jobs": N, "ok": N, "bags": N, "frames": N, "statuses": {..}, "errors": [..]}
Exit 0 when no errors, 1 with errors, 2 when pandas or rosbags is missing.
"""
import hashlib
import json
import sys
from pathlib import Path

try:
    import pandas as pd
    from rosbags.highlevel import AnyReader
except ImportError as exc:
    print(f"pandas or rosbags is not importable ({exc}): pip install -r tests/py/requirements.txt",
          file=sys.stderr)
    sys.exit(2)

KEYS = {"substeps", "subdivisions", "cg_iterations", "cg_residual_max", "contacts",
        "deepest_penetration_m", "max_edge_stretch", "energy_j"}


def check_bag(path, errors):
    meshes, diags = [], {}
    with AnyReader([path]) as reader:
        for conn, t, raw in reader.messages():
            if conn.topic == "/drape/mesh":
                meshes.append(t)
            elif conn.topic == "/diagnostics":
                msg = reader.deserialize(raw, conn.msgtype)
                keys = {kv.key for st in msg.status for kv in st.values}
                diags[t] = keys
    for t in meshes:
        if t not in diags:
            errors.append(f"{path}: frame at {t} ns has no /diagnostics")
        elif not KEYS <= diags[t]:
            errors.append(f"{path}: frame at {t} ns lacks {sorted(KEYS - diags[t])}")
    return len(meshes)


def main(out):
    out = Path(out)
    errors = []
    jl = pd.read_json(out / "manifest.jsonl", lines=True)
    csv = pd.read_csv(out / "manifest.csv")
    if list(jl["index"]) != list(csv["index"]) or list(jl["status"]) != list(csv["status"]):
        errors.append("manifest.jsonl and manifest.csv disagree on index/status")
    frames = bags = 0
    for row in jl.itertuples():
        if row.status != "ok":
            continue
        bag = out / row.bag
        data = bag.read_bytes()
        if len(data) != row.size:
            errors.append(f"{bag}: {len(data)} bytes, manifest says {row.size}")
        if hashlib.sha256(data).hexdigest() != row.sha256:
            errors.append(f"{bag}: sha256 differs from the manifest")
        n = check_bag(bag, errors)
        if n != row.summary["frames"]:
            errors.append(f"{bag}: {n} frames, summary says {row.summary['frames']}")
        frames += n
        bags += 1
    json.dump({"jobs": int(len(jl)), "ok": int((jl["status"] == "ok").sum()), "bags": bags,
               "frames": frames, "statuses": {k: int(v) for k, v in jl["status"].value_counts().items()},
               "errors": errors[:20]}, sys.stdout)
    sys.exit(1 if errors else 0)


if __name__ == "__main__":
    try:
        main(sys.argv[1])
    except Exception as exc:  # report, do not trace back: the Rust test prints this
        print(f"cannot check {sys.argv[1]}: {exc!r}", file=sys.stderr)
        sys.exit(1)
