#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Checks that pickdetect-eval's C++ metrics and the independent score.py agree.

    agree.py PICKDETECT_EVAL SCORE_PY DATASET DETECTIONS

Runs `PICKDETECT_EVAL --score DETECTIONS --json DATASET` and `SCORE_PY DATASET DETECTIONS`
and compares every figure of every method and model to 1e-6 (null must meet null).
"""
import json
import subprocess
import sys

KEYS = ["object_precision", "object_recall", "pixel_precision", "pixel_recall",
        "center_mean_px", "center_p95_px", "points_mean_px", "pick_precision", "pick_recall",
        "tp", "fp", "fn", "ms_per_frame"]
TRACKING_KEYS = ["mota", "idf1", "id_switches", "fragmented", "ghosts", "objects_present",
                 "objects_counted", "required", "detections", "fn", "fp", "idtp"]
TOLERANCE = 1e-6


def run(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        sys.exit("%s failed (%d): %s" % (cmd[0], p.returncode, p.stderr))
    return json.loads(p.stdout)


def compare(a, b, where, problems, keys=KEYS):
    if set(a) != set(keys) or set(b) != set(keys):
        problems.append("%s: keys differ from %s: %s / %s" % (where, sorted(keys), sorted(a), sorted(b)))
        return
    for k in keys:
        x, y = a[k], b[k]
        if x is None or y is None:
            if x is not y:
                problems.append("%s.%s: C++ %r, score.py %r" % (where, k, x, y))
        elif abs(x - y) > TOLERANCE:
            problems.append("%s.%s: C++ %r, score.py %r" % (where, k, x, y))


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    tool, score, dataset, detections = sys.argv[1:]
    cpp = run([tool, "--score", detections, "--json", dataset])
    py = run([sys.executable, score, dataset, detections])
    problems = []
    if set(cpp["methods"]) != set(py["methods"]):
        problems.append("methods differ: %s / %s" % (sorted(cpp["methods"]), sorted(py["methods"])))
    compared = 0
    for method in sorted(set(cpp["methods"]) & set(py["methods"])):
        a, b = cpp["methods"][method], py["methods"][method]
        compare(a["overall"], b["overall"], method + ".overall", problems)
        compared += 1
        if set(a["models"]) != set(b["models"]):
            problems.append("%s: models differ" % method)
        for model in sorted(set(a["models"]) & set(b["models"])):
            compare(a["models"][model], b["models"][model], "%s.%s" % (method, model), problems)
            compared += 1
    if ("paired_centers" in cpp) != ("paired_centers" in py):
        problems.append("paired_centers: in one report only")
    elif "paired_centers" in cpp:
        a, b = cpp["paired_centers"], py["paired_centers"]
        if a["instances"] != b["instances"]:
            problems.append("paired_centers.instances: C++ %r, score.py %r"
                            % (a["instances"], b["instances"]))
        compare(a["center_mean_px"], b["center_mean_px"], "paired_centers", problems,
                keys=sorted(set(a["center_mean_px"]) | set(b["center_mean_px"])))
        compared += 1
    for method in sorted(set(cpp["methods"]) & set(py["methods"])):
        a, b = cpp["methods"][method].get("tracking"), py["methods"][method].get("tracking")
        if (a is None) != (b is None):
            problems.append("%s.tracking: in one report only" % method)
        elif a is not None:
            compare(a, b, method + ".tracking", problems, keys=TRACKING_KEYS)
            compared += 1
    for p in problems:
        print("DISAGREE " + p)
    if compared == 0:
        problems.append("nothing compared")
    print("%d summaries compared, %d disagreements" % (compared, len(problems)))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
