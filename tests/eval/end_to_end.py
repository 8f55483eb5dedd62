#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""End to end: pickdetect-synth makes a tiny dataset, pickdetect-eval runs it through the real
pickdetect element, and score.py rescoring its --detections-out agrees with its --json.

    end_to_end.py PICKDETECT_SYNTH PICKDETECT_EVAL SCORE_PY MODEL_PICTURE [SECOND_PICTURE]

Also checks that the element finds as much in frames with a fifth of the light or of the
contrast (--frame-gain, --frame-contrast), and that a dataset with a broken field is refused with the file and field named. With
a second picture, a two-product dataset runs with both models in one element (the default),
with --per-model and with --models.
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


def agree(voting, again):
    bad = [("overall", k) for k in KEYS if not close(voting["overall"][k], again["overall"][k])]
    for model in voting["models"]:
        bad += [(model, k) for k in KEYS
                if not close(voting["models"][model][k], again["models"][model][k])]
    assert not bad, "pickdetect-eval and score.py disagree on %s" % bad


def two_products(synth, tool, score, pictures, tmp):
    data = os.path.join(tmp, "mixed")
    run([synth, "--scenes", "2", "--size", "800x600", "--instances", "3-3", "--scale", "0.5-0.6",
         "--tilt", "0", "--kind", "conveyor", "--distractors", "0", "--seed", "4", "--format",
         "png", "--mixed-products", "--out", data] + pictures)
    models = sorted(json.load(open(os.path.join(data, "dataset.json")))["models"])
    assert len(models) == 2, models

    # Default: one element with both models; one time per frame, none per model.
    det = os.path.join(tmp, "mixed.jsonl")
    report = json.loads(run([tool, "--method", "voting", "--json", "--detections-out", det,
                             data]).stdout)["methods"]["voting"]
    print("both models in one element:", json.dumps(report["overall"]))
    assert sorted(report["models"]) == models
    assert report["overall"]["tp"] >= 4, report["overall"]
    for m in models:
        assert report["models"][m]["tp"] >= 1, (m, report["models"][m])
        assert report["models"][m]["ms_per_frame"] is None, report["models"][m]
    assert report["overall"]["ms_per_frame"] > 0
    lines = [json.loads(l) for l in open(det)]
    assert all("frame_ms" in l and "ms" not in l for l in lines), lines
    assert {i["model"] for l in lines for i in l["instances"]} == set(models)
    agree(report, json.loads(run([sys.executable, score, data, det]).stdout)["methods"]
          ["detections"])

    # --per-model: one element per model, a time per model.
    det = os.path.join(tmp, "per-model.jsonl")
    per = json.loads(run([tool, "--method", "voting", "--per-model", "--json",
                          "--detections-out", det, data]).stdout)["methods"]["voting"]
    for m in models:
        assert per["models"][m]["ms_per_frame"] > 0, per["models"][m]
    lines = [json.loads(l) for l in open(det)]
    assert all(sorted(l["ms"]) == models and "frame_ms" not in l for l in lines), lines
    agree(per, json.loads(run([sys.executable, score, data, det]).stdout)["methods"]
          ["detections"])

    # --models: only that model is loaded and scored.
    only = json.loads(run([tool, "--method", "voting", "--models", models[0], "--json",
                           data]).stdout)["methods"]["voting"]
    assert only["models"][models[1]]["tp"] == 0 and only["models"][models[1]]["fp"] == 0
    assert only["models"][models[1]]["object_recall"] is None
    assert only["overall"]["tp"] == only["models"][models[0]]["tp"] >= 1, only
    err = run([tool, "--models", "nothing", data], expect=2).stderr
    assert "'nothing' is not one of the dataset's models" in err, err


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
        agree(voting, rescored["methods"]["detections"])

        # The same frames with a fifth of the light, then flattened to a fifth of their contrast:
        # the element finds what it found in full light.
        for light in (["--frame-gain", "0.2"], ["--frame-contrast", "0.2"]):
            dim = json.loads(run([tool, "--method", "voting", "--json", data] + light).stdout)
            dim = dim["methods"]["voting"]["overall"]
            print("element with %s:" % " ".join(light), json.dumps(dim))
            assert dim["tp"] >= overall["tp"] and dim["fp"] == 0, (light, dim)
        err = run([tool, "--frame-gain", "0", data], expect=2).stderr
        assert "--frame-gain wants 0 < G <= 4, got 0" in err, err

        # A broken dataset is refused, naming the file and the field.
        broken = os.path.join(tmp, "broken")
        shutil.copytree(data, broken)
        doc = json.load(open(os.path.join(broken, "dataset.json")))
        doc["scenes"][1]["width"] = "wide"
        json.dump(doc, open(os.path.join(broken, "dataset.json"), "w"))
        err = run([tool, "--method", "voting", broken], expect=1).stderr
        assert "dataset.json: scenes[1].width" in err, err

        if len(sys.argv) > 5:
            two_products(synth, tool, score, [picture, sys.argv[5]], tmp)
        print("ok")
        return 0
    finally:
        shutil.rmtree(tmp)


if __name__ == "__main__":
    sys.exit(main())
