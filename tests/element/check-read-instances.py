#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Runs pipelines/read-instances.py on OpenCV's box_in_scene.png (model box.png) and checks that
it prints, for each of the 3 frames, one instance line with the box where it is in the picture,
under one track id.

Usage: check-read-instances.py READ_INSTANCES_PY BUILD_DIR DATA_DIR
"""
import os
import re
import subprocess
import sys

script, build_dir, data_dir = sys.argv[1:4]
env = dict(os.environ, PICKDETECT_BUILD_DIR=build_dir)
env.pop("GST_PLUGIN_PATH", None)  # The script must find the plugin from the build folder alone.
result = subprocess.run(
    [sys.executable, script, "--frames", "3", "--model", os.path.join(data_dir, "box.png"),
     os.path.join(data_dir, "box_in_scene.png")],
    env=env, capture_output=True, text=True, timeout=300)
sys.stdout.write(result.stdout)
sys.stderr.write(result.stderr)
if result.returncode != 0:
    sys.exit("read-instances.py failed with status %d" % result.returncode)

# The box in box_in_scene.png: centre near (187, 224), turned a little clockwise, about half size.
# The basmati box lies on its right edge and a bag on a corner: covered, not to be picked.
line = re.compile(r"^frame=(\d+) pts=\S+ roi=\d+ model=box center=\(([\d.]+),([\d.]+)\) "
                  r"angle=([\d.]+) scale=([\d.]+) score=([\d.]+) matches=(\d+) .*covered=yes pickable=no "
                  r"pick-order=0 .*bbox=\d+,\d+\+\d+x\d+ points=5 track=(\d+)$")
frames = []
tracks = set()
for text in result.stdout.splitlines():
    m = line.match(text)
    if not m:
        sys.exit("unexpected line: %r" % text)
    frame, x, y, angle, scale, score, matches, track = m.groups()
    tracks.add(int(track))
    x, y, angle, scale = float(x), float(y), float(angle), float(scale)
    if abs(x - 187) > 5 or abs(y - 224) > 5:
        sys.exit("box centre (%.1f, %.1f) is not near (187, 224)" % (x, y))
    if min(abs(angle - 9), 360 - abs(angle - 9)) > 5 or abs(scale - 0.53) > 0.05:
        sys.exit("box pose angle %.1f scale %.3f, expected about 9 and 0.53" % (angle, scale))
    if int(matches) < 20:
        sys.exit("only %s matches" % matches)
    frames.append(int(frame))
if frames != [0, 1, 2]:
    sys.exit("expected one instance in each of frames 0, 1, 2, got frames %s" % frames)
if len(tracks) != 1 or 0 in tracks:
    sys.exit("the one box should keep one track id over the three frames, got %s" % sorted(tracks))
print("read-instances.py: ok")
