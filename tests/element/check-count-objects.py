#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Runs pipelines/count-objects.py on a belt sequence made by pickdetect-synth and checks that it
counts each object that crosses the line exactly once, as many as the truth says cross it.

Usage: check-count-objects.py COUNT_OBJECTS_PY BUILD_DIR DATA_DIR
"""
import collections
import json
import os
import re
import subprocess
import sys
import tempfile

script, build_dir, data_dir = sys.argv[1:4]
synth = os.path.join(build_dir, "tools", "synth", "pickdetect-synth")
line_x = 320
with tempfile.TemporaryDirectory(prefix="pickdetect-count-") as out:
    subprocess.run([synth, "--sequence", "conveyor", "--size", "640x480", "--scenes", "60",
                    "--scale", "0.35-0.4", "--seed", "3", "--out", out,
                    os.path.join(data_dir, "box.png")], check=True, capture_output=True,
                   timeout=300)
    truth = json.load(open(os.path.join(out, "dataset.json")))
    env = dict(os.environ, PICKDETECT_BUILD_DIR=build_dir)
    env.pop("GST_PLUGIN_PATH", None)
    result = subprocess.run(
        [sys.executable, script, "--model", os.path.join(data_dir, "box.png"),
         "--line", "%d,0,%d,480" % (line_x, line_x), "--fps", str(int(truth["fps"])),
         os.path.join(out, "scenes", "%04d.jpg")],
        env=env, capture_output=True, text=True, timeout=300)
sys.stdout.write(result.stdout)
sys.stderr.write(result.stderr)
if result.returncode != 0:
    sys.exit("count-objects.py failed with status %d" % result.returncode)

# The truth: the objects whose centre is seen on both sides of the line.
sides = collections.defaultdict(set)
for scene in truth["scenes"]:
    for inst in scene["instances"]:
        if inst["points"] and inst["visible"] >= 0.3:
            sides[inst["track"]].add(inst["points"][0][0] >= line_x)
expected = sum(1 for s in sides.values() if s == {False, True})

counted = re.compile(r"^counted model=box track=(\d+) count=(\d+) total=(\d+) time=\S+$")
tracks, counts = [], []
lines = result.stdout.splitlines()
for text in lines[:-1]:
    m = counted.match(text)
    if not m:
        sys.exit("unexpected line: %r" % text)
    tracks.append(int(m.group(1)))
    counts.append(int(m.group(2)))
if lines[-1] != "total=%d box=%d" % (len(tracks), len(tracks)) and not (
        not tracks and lines[-1] == "total=0"):
    sys.exit("unexpected totals line: %r" % lines[-1])
if len(set(tracks)) != len(tracks):
    sys.exit("a track was counted twice: %s" % tracks)
if counts != list(range(1, len(counts) + 1)):
    sys.exit("the running count should go 1, 2, 3...: %s" % counts)
if len(tracks) != expected:
    sys.exit("counted %d objects, %d crossed the line" % (len(tracks), expected))
print("count-objects.py: ok (%d counted)" % len(tracks))
