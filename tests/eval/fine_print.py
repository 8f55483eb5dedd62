#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""A bin of four products made from OpenCV's sample pictures, one of them a fine graffiti print,
beside striped distractors: the real element reports every object and no object where there is
none, frame by frame and as a stream. Frame by frame, the graffiti print was found at twice its
size on keypoints along the stripes and a box's edge (docs/accuracy.md, "Keypoints the pixels
deny").

    fine_print.py PICKDETECT_SYNTH PICKDETECT_EVAL DATA_DIR
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

PICTURES = ["box.png", "graf1.png", "HappyFish.jpg", "aero3.jpg"]


def run(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        sys.exit("%s exited %d: %s" % (" ".join(cmd), p.returncode, p.stderr))
    return p.stdout


def main():
    synth, tool, data_dir = sys.argv[1:4]
    tmp = tempfile.mkdtemp(prefix="pickdetect-fine-print-")
    try:
        data = os.path.join(tmp, "bin")
        # The first two frames of docs/tracking.md's bin of other products.
        run([synth, "--sequence", "bin", "--instances", "8-8", "--pick-every", "12", "--scale",
             "0.4-0.5", "--scenes", "2", "--seed", "13", "--out", data]
            + [os.path.join(data_dir, p) for p in PICTURES])
        for extra in (["--set", "tracking=false"], []):
            report = json.loads(run([tool, "--method", "voting", "--json", data] + extra))
            voting = report["methods"]["voting"]
            overall = voting["overall"]
            print("element %s:" % (" ".join(extra) or "as a stream"), json.dumps(overall))
            ghosts = {m: r["fp"] for m, r in voting["models"].items() if r["fp"]}
            assert not ghosts, "instances where there is none: %s" % ghosts
            assert overall["fn"] == 0 and overall["tp"] >= 8, overall
        print("ok")
        return 0
    finally:
        shutil.rmtree(tmp)


if __name__ == "__main__":
    sys.exit(main())
