#!/usr/bin/env python3
"""Opaque frames before and after alpha-tested casters: the same command run with the binary
of commit 5a3262e (BEFORE) and of this tree (AFTER), interleaved, medians of N runs.

Usage: BEFORE=old/manyshadows AFTER=target/release/manyshadows python3 opaque_speed.py [N] [technique,...]
"""
import json, os, statistics, subprocess, sys
OLD, NEW = os.environ["BEFORE"], os.environ["AFTER"]  # two manyshadows binaries
N = int(sys.argv[1]) if len(sys.argv) > 1 else 5
ALL = [("dragon", t) for t in ["traditional", "layered", "gpu-driven", "compute", "irregular", "virtual"]] + \
      [("terrain", "traditional"), ("terrain", "layered")]
cases = [c for c in ALL if c[1] in sys.argv[2].split(",")] if len(sys.argv) > 2 else ALL
env = dict(os.environ, WGPU_BACKEND=os.environ.get("WGPU_BACKEND", "vulkan"), XDG_RUNTIME_DIR=os.environ.get("XDG_RUNTIME_DIR", "/tmp"))
rows = []
for scene, tech in cases:
    res = {"before": [], "after": []}
    for k in range(N + 1):  # first round is a warm-up
        for label, exe in (("before", OLD), ("after", NEW)) if k % 2 == 0 else (("after", NEW), ("before", OLD)):
            out = f"/tmp/os-{label}.json"
            subprocess.run([exe, "render", "--scene", scene, "--technique", tech, "--lights", "16",
                            "--width", "640", "--height", "360", "--json", out, "--out", "/tmp/os.png"],
                           env=env, check=True, capture_output=True)
            if k > 0:
                d = json.load(open(out))
                g = d["gpu_ms"]
                res[label].append((g.get("shadows", 0.0) + g.get("pages", 0.0), sum(g.values()), d["adapter"]))
    med = {l: (statistics.median(x[0] for x in v), statistics.median(x[1] for x in v)) for l, v in res.items()}
    rows.append((scene, tech, med))
    print(f"{scene:8} {tech:12} shadows {med['before'][0]:8.1f} -> {med['after'][0]:8.1f} ms ({med['after'][0]/med['before'][0]:.3f}x)"
          f"   GPU frame {med['before'][1]:8.1f} -> {med['after'][1]:8.1f} ms ({med['after'][1]/med['before'][1]:.3f}x)", flush=True)
print("adapter:", res["after"][0][2])
