#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""End to end: pickdetect-synth makes a tiny dataset, pickdetect-eval runs it through the real
pickdetect element, and score.py rescoring its --detections-out agrees with its --json.

    end_to_end.py PICKDETECT_SYNTH PICKDETECT_EVAL SCORE_PY MODEL_PICTURE

Also checks that a dataset with a broken field is refused with the file and field named.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

KEYS = ["object_precision", "object_recall", "pixel_precision", "pixel_recall",
        "center_mean_px", "center_p95_px", "points_mean_px", "pick_precision", "pick_recall",
        "tp", "fp", "fn", "ms_per_frame"]


def run(cmd, expect=0):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if (p.returncode == 0) != (expect == 0):
        sys.exit("%s exited %d: %s" % (" ".join(cmd), p.returncode, p.stderr))
    return p


def close(a, b):
    if a is None or b is None:
        return a is b
    return abs(a - b) <= 1e-6


def main():
    synth, tool, score, picture = sys.argv[1:5]
    tmp = tempfile.mkdtemp(prefix="pickdetect-e2e-")
    try:
        data = os.path.join(tmp, "set")
        run([synth, "--scenes", "2", "--size", "640x480", "--instances", "2-3", "--scale",
             "0.8-0.9", "--tilt", "0", "--kind", "conveyor", "--distractors", "0", "--seed", "4",
             "--format", "png", "--out", data, picture])
        det = os.path.join(tmp, "det.jsonl")
        out = run([tool, "--method", "voting", "--json", "--detections-out", det, data]).stdout
        report = json.loads(out)
        voting = report["methods"]["voting"]
        assert set(voting["overall"]) == set(KEYS), sorted(voting["overall"])
        overall = voting["overall"]
        print("element on the tiny set:", json.dumps(overall))
        required = overall["tp"] + overall["fn"]
        assert required >= 4, "synth made too few required instances: %d" % required
        assert overall["tp"] >= 1, "the element found nothing on clean conveyor scenes"
        assert overall["ms_per_frame"] and overall["ms_per_frame"] > 0
        lines = [json.loads(l) for l in open(det)]
        assert [l["image"] for l in lines] == ["scenes/0000.png", "scenes/0001.png"], lines
        rescored = json.loads(run([sys.executable, score, data, det]).stdout)
        # One method: the lines carry no "method" key and score.py names the set "detections".
        again = rescored["methods"]["detections"]
        bad = [(scope, k) for scope in ["overall"] for k in KEYS
               if not close(voting[scope][k], again[scope][k])]
        for model in voting["models"]:
            bad += [(model, k) for k in KEYS
                    if not close(voting["models"][model][k], again["models"][model][k])]
        assert not bad, "pickdetect-eval and score.py disagree on %s" % bad

        # A broken dataset is refused, naming the file and the field.
        broken = os.path.join(tmp, "broken")
        shutil.copytree(data, broken)
        doc = json.load(open(os.path.join(broken, "dataset.json")))
        doc["scenes"][1]["width"] = "wide"
        json.dump(doc, open(os.path.join(broken, "dataset.json"), "w"))
        err = run([tool, "--method", "voting", broken], expect=1).stderr
        assert "dataset.json: scenes[1].width" in err, err
        print("ok")
        return 0
    finally:
        shutil.rmtree(tmp)


if __name__ == "__main__":
    sys.exit(main())
