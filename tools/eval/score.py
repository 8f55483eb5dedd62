#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Independent scorer for the pickdetect benchmark (Python 3 standard library only).

    score.py DATASET_DIR_OR_JSON DETECTIONS.jsonl [--method NAME]

Reads a dataset.json and a detections JSON Lines file (see the benchmark's FORMAT.md) and
prints, as JSON, the figures per method (lines without a "method" key form the method
"detections"), overall and per model:

    {"dataset": NAME, "methods": {METHOD: {"overall": {...}, "models": {MODEL: {...}}}}}

It is written apart from pickdetect-eval's C++ metric code, from FORMAT.md, so that the two can
check each other. The choices FORMAT.md leaves open are made the same way (see metrics.hpp):
exact polygon areas (Sutherland-Hodgman clipping against convex regions, fan triangulation for
non-convex pairs, shoelace areas; a self-crossing outline scored as its convex hull), greedy matching by descending IoU with ties to the earlier
detection then the earlier instance, don't-care instances matched like others but counted
neither way, linear-interpolated percentiles, pick figures only over scenes where every instance
has "covered", undefined ratios as null, ms_per_frame the median (overall: of the per-frame
time, "frame_ms" plus the sum of "ms" over models).
"""

import argparse
import json
import math
import os
import sys

DONT_CARE_VISIBLE = 0.3
MATCH_IOU = 0.5
PICK_COVERED = 0.02
KEYS = ["object_precision", "object_recall", "pixel_precision", "pixel_recall",
        "center_mean_px", "center_p95_px", "points_mean_px", "pick_precision", "pick_recall",
        "tp", "fp", "fn", "ms_per_frame"]


class FormatError(Exception):
    pass


# ---------------------------------------------------------------- geometry

def shoelace(poly):
    n = len(poly)
    if n < 3:
        return 0.0
    s = 0.0
    for i in range(n):
        x0, y0 = poly[i]
        x1, y1 = poly[(i + 1) % n]
        s += x0 * y1 - x1 * y0
    return s / 2.0


def ccw(poly):
    return list(poly) if shoelace(poly) >= 0.0 else list(reversed(poly))


def turn(a, b, p):
    return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])


def convex(poly):
    n = len(poly)
    if n < 3:
        return False
    signs = set()
    for i in range(n):
        c = turn(poly[i], poly[(i + 1) % n], poly[(i + 2) % n])
        if c > 0:
            signs.add(1)
        elif c < 0:
            signs.add(-1)
    return len(signs) < 2


def crosses(poly):
    """Two edges without a common vertex cross properly."""
    n = len(poly)

    def opposite(a, b):
        return (a > 0.0 and b < 0.0) or (a < 0.0 and b > 0.0)

    for i in range(n):
        a, b = poly[i], poly[(i + 1) % n]
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            c, d = poly[j], poly[(j + 1) % n]
            if opposite(turn(a, b, c), turn(a, b, d)) and opposite(turn(c, d, a), turn(c, d, b)):
                return True
    return False


def hull(poly):
    """Andrew's monotone chain, counter-clockwise, no collinear points."""
    pts = sorted(poly)
    if len(pts) < 3:
        return pts
    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and turn(lower[-2], lower[-1], p) <= 0.0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and turn(upper[-2], upper[-1], p) <= 0.0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def normal(poly):
    """The outline as scored: a self-crossing one is replaced by its convex hull."""
    return ccw(hull(poly) if crosses(poly) else poly)


def clip(subject, clipper):
    """Sutherland-Hodgman: subject (any polygon) inside the convex clipper."""
    if len(subject) < 3 or len(clipper) < 3:
        return []
    c = ccw(clipper)
    out = list(subject)
    for i in range(len(c)):
        if not out:
            break
        a, b = c[i], c[(i + 1) % len(c)]
        src, out = out, []
        for j in range(len(src)):
            p, q = src[j], src[(j + 1) % len(src)]
            tp, tq = turn(a, b, p), turn(a, b, q)
            if tp >= 0.0:
                out.append(p)
            if (tp >= 0.0) != (tq >= 0.0):
                t = tp / (tp - tq)
                out.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return out


def frame_clip(poly, w, h):
    return clip(poly, [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)])


def inter_area(a, b):
    if len(a) < 3 or len(b) < 3:
        return 0.0
    a, b = ccw(a), ccw(b)
    if convex(b):
        return max(0.0, shoelace(clip(a, b)))
    if convex(a):
        return max(0.0, shoelace(clip(b, a)))
    total = 0.0
    for i in range(1, len(b) - 1):
        tri = [b[0], b[i], b[i + 1]]
        o = shoelace(tri)
        if o == 0.0:
            continue
        piece = shoelace(clip(a, tri))
        total += piece if o > 0 else -piece
    return max(0.0, total)


def overlap(d, g, w, h):
    """(|D|, |G|, |D n G|), all clipped to the frame."""
    cd, cg = frame_clip(normal(d), w, h), frame_clip(normal(g), w, h)
    ad, ag = max(0.0, shoelace(cd)), max(0.0, shoelace(cg))
    return ad, ag, min(inter_area(cd, cg), ad, ag)


def iou(ad, ag, ai):
    u = ad + ag - ai
    return ai / u if u > 0.0 else 0.0


# ---------------------------------------------------------------- reading

def need(obj, key, where, origin):
    if not isinstance(obj, dict):
        raise FormatError("%s: %s: expected an object" % (origin, where or "top level"))
    if key not in obj:
        raise FormatError("%s: %s: missing" % (origin, (where + "." if where else "") + key))
    return obj[key]


def number(v, where, origin):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise FormatError("%s: %s: expected a number" % (origin, where))
    return float(v)


def points(v, where, origin, least=0):
    if not isinstance(v, list):
        raise FormatError("%s: %s: expected an array" % (origin, where))
    out = []
    for i, p in enumerate(v):
        if not isinstance(p, list) or len(p) != 2:
            raise FormatError("%s: %s[%d]: expected an [x, y] pair" % (origin, where, i))
        out.append((number(p[0], "%s[%d][0]" % (where, i), origin),
                    number(p[1], "%s[%d][1]" % (where, i), origin)))
    if len(out) < least:
        raise FormatError("%s: %s: needs at least %d points" % (origin, where, least))
    return out


def load_dataset(path):
    if os.path.isdir(path):
        path = os.path.join(path, "dataset.json")
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except (OSError, ValueError) as e:
        raise FormatError("%s: %s" % (path, e))
    models = need(doc, "models", "", path)
    if not isinstance(models, dict) or not models:
        raise FormatError("%s: models: expected a non-empty object" % path)
    ds = {"name": doc.get("name", os.path.basename(os.path.dirname(os.path.abspath(path)))),
          "models": {}, "model_order": list(models), "scenes": [], "fps": None}
    if "fps" in doc:
        ds["fps"] = number(doc["fps"], "fps", path)
        if not ds["fps"] > 0:
            raise FormatError("%s: fps: must be positive" % path)
    for name, m in models.items():
        w = "models." + name
        ds["models"][name] = {
            "principal_points": points(need(m, "principal_points", w, path),
                                       w + ".principal_points", path, 1),
            "polygon": points(need(m, "polygon", w, path), w + ".polygon", path, 3)}
    for si, s in enumerate(need(doc, "scenes", "", path)):
        w = "scenes[%d]" % si
        scene = {"image": need(s, "image", w, path),
                 "width": number(need(s, "width", w, path), w + ".width", path),
                 "height": number(need(s, "height", w, path), w + ".height", path),
                 "instances": []}
        for ii, t in enumerate(need(s, "instances", w, path)):
            wi = "%s.instances[%d]" % (w, ii)
            model = need(t, "model", wi, path)
            if model not in ds["models"]:
                raise FormatError("%s: %s.model: '%s' is not one of the dataset's models"
                                  % (path, wi, model))
            visible = number(need(t, "visible", wi, path), wi + ".visible", path)
            # A don't-care instance (a look-alike surface listed with visible 0) may leave its
            # points out: it is never scored by them.
            least = 0 if visible < DONT_CARE_VISIBLE else 1
            inst = {"model": model,
                    "points": points(need(t, "points", wi, path), wi + ".points", path, least),
                    "polygon": points(need(t, "polygon", wi, path), wi + ".polygon", path, 3),
                    "visible": visible,
                    "covered": None}
            if "covered" in t:
                inst["covered"] = number(t["covered"], wi + ".covered", path)
            inst["track"] = t.get("track")
            if ds["fps"] is not None and inst["track"] is None:
                raise FormatError("%s: %s.track: missing (a video sequence, with fps, gives every "
                                  "instance one)" % (path, wi))
            scene["instances"].append(inst)
        ds["scenes"].append(scene)
    return ds


def load_detections(path):
    lines = []
    with open(path, encoding="utf-8") as f:
        for n, text in enumerate(f, 1):
            if not text.strip():
                continue
            origin = "%s:%d" % (path, n)
            try:
                doc = json.loads(text)
            except ValueError as e:
                raise FormatError("%s: not valid JSON: %s" % (origin, e))
            insts = []
            for i, d in enumerate(need(doc, "instances", "", origin)):
                w = "instances[%d]" % i
                insts.append({
                    "model": need(d, "model", w, origin),
                    "points": points(need(d, "points", w, origin), w + ".points", origin, 1),
                    "polygon": points(need(d, "polygon", w, origin), w + ".polygon", origin, 3),
                    "pickable": bool(d.get("pickable", False)),
                    "track": int(d["track"]) if d.get("track") is not None else None})
            lines.append({"image": need(doc, "image", "", origin),
                          "method": doc.get("method", ""),
                          "ms": {k: float(v) for k, v in doc.get("ms", {}).items()},
                          "frame_ms": float(doc["frame_ms"]) if "frame_ms" in doc else None,
                          "instances": insts})
    return lines


# ---------------------------------------------------------------- scoring

def new_tally():
    return {"tp": 0, "fp": 0, "required": 0, "inter": 0.0, "det": 0.0, "true": 0.0,
            "centers": [], "pt_sum": 0.0, "pt_n": 0, "flagged": 0, "safe": 0,
            "pick_req": 0, "pick_found": 0, "ms": []}


def score_scene(tally, scene, dets, model, centers_by_truth):
    w, h = scene["width"], scene["height"]
    insts = scene["instances"]
    pick_known = all(t["covered"] is not None for t in insts)
    cands = []
    for di, d in enumerate(dets):
        if d["model"] != model:
            continue
        for gi, g in enumerate(insts):
            if g["model"] != model:
                continue
            v = iou(*overlap(d["polygon"], g["polygon"], w, h))
            if v >= MATCH_IOU:
                cands.append((-v, di, gi))
    cands.sort()
    det_pair, inst_pair = {}, {}
    for _, di, gi in cands:
        if di in det_pair or gi in inst_pair:
            continue
        det_pair[di], inst_pair[gi] = gi, di
    for di, d in enumerate(dets):
        if d["model"] != model:
            continue
        gi = det_pair.get(di)
        if pick_known and d["pickable"]:
            tally["flagged"] += 1
            if gi is not None and insts[gi]["covered"] < PICK_COVERED:
                tally["safe"] += 1
        if gi is None:
            tally["fp"] += 1
            tally["det"] += max(0.0, shoelace(frame_clip(normal(d["polygon"]), w, h)))
            continue
        g = insts[gi]
        if g["visible"] < DONT_CARE_VISIBLE:
            continue
        tally["tp"] += 1
        ad, _, ai = overlap(d["polygon"], g["polygon"], w, h)
        tally["inter"] += ai
        tally["det"] += ad
        tally["centers"].append(math.hypot(d["points"][0][0] - g["points"][0][0],
                                           d["points"][0][1] - g["points"][0][1]))
        centers_by_truth[gi] = tally["centers"][-1]
        for p, q in zip(d["points"], g["points"]):
            tally["pt_sum"] += math.hypot(p[0] - q[0], p[1] - q[1])
            tally["pt_n"] += 1
    for gi, g in enumerate(insts):
        if g["model"] != model or g["visible"] < DONT_CARE_VISIBLE:
            continue
        tally["required"] += 1
        tally["true"] += max(0.0, shoelace(frame_clip(normal(g["polygon"]), w, h)))
        if pick_known and g["covered"] < PICK_COVERED:
            tally["pick_req"] += 1
            di = inst_pair.get(gi)
            if di is not None and dets[di]["pickable"]:
                tally["pick_found"] += 1


def pair_detections(scene, dets, model):
    """Detection index -> true instance index, FORMAT.md's per-frame pairing for one model."""
    w, h = scene["width"], scene["height"]
    cands = []
    for di, d in enumerate(dets):
        if d["model"] != model:
            continue
        for gi, g in enumerate(scene["instances"]):
            if g["model"] == model:
                v = iou(*overlap(d["polygon"], g["polygon"], w, h))
                if v >= MATCH_IOU:
                    cands.append((-v, di, gi))
    cands.sort()
    det_pair, taken = {}, set()
    for _, di, gi in cands:
        if di not in det_pair and gi not in taken:
            det_pair[di] = gi
            taken.add(gi)
    return det_pair


TRACK_MIN_FRAMES = 5


def score_tracking(ds, by_scene):
    """FORMAT.md's tracking figures of a video sequence (choices as tracking.hpp's)."""
    required = detections = fn = fp = switches = 0
    last, ids_of, req_frames, shared, id_frames = {}, {}, {}, {}, {}
    for si, scene in enumerate(ds["scenes"]):
        dets = by_scene.get(si, {"instances": []})["instances"]
        for i in {d["track"] for d in dets if d["track"] is not None}:
            id_frames[i] = id_frames.get(i, 0) + 1
        paired = set()
        for m in ds["model_order"]:
            for di, gi in sorted(pair_detections(scene, dets, m).items()):
                g = scene["instances"][gi]
                if g["visible"] < DONT_CARE_VISIBLE:
                    continue
                paired.add(gi)
                obj, tid = g["track"], dets[di]["track"]
                if obj in last and last[obj] != tid:
                    switches += 1
                last[obj] = tid
                if tid is not None:
                    ids_of.setdefault(obj, set()).add(tid)
                    shared[(obj, tid)] = shared.get((obj, tid), 0) + 1
            n_model = sum(1 for d in dets if d["model"] == m)
            n_paired = len(pair_detections(scene, dets, m))
            fp += n_model - n_paired
        detections += fp_scene_free(scene, dets, ds)
        for gi, g in enumerate(scene["instances"]):
            if g["visible"] < DONT_CARE_VISIBLE:
                continue
            required += 1
            req_frames[g["track"]] = req_frames.get(g["track"], 0) + 1
            if gi not in paired:
                fn += 1
    idtp, objs, ids = 0, set(), set()
    for (obj, tid), n in sorted(shared.items(), key=lambda kv: (-kv[1], kv[0][0], kv[0][1])):
        if obj not in objs and tid not in ids:
            objs.add(obj)
            ids.add(tid)
            idtp += n
    present = [o for o, n in req_frames.items() if n >= TRACK_MIN_FRAMES]
    return {"mota": 1 - (fn + fp + switches) / required if required else None,
            "idf1": 2 * idtp / (required + detections) if required + detections else None,
            "id_switches": switches,
            "fragmented": sum(1 for o in present if len(ids_of.get(o, ())) > 1),
            "ghosts": sum(1 for i, n in id_frames.items() if n >= TRACK_MIN_FRAMES and i not in ids),
            "objects_present": len(present),
            "objects_counted": sum(1 for o in present if o in objs),
            "required": required, "detections": detections, "fn": fn, "fp": fp, "idtp": idtp}


def fp_scene_free(scene, dets, ds):
    """The detections of a frame that count: those not paired with a don't-care instance."""
    n = 0
    for m in ds["model_order"]:
        pairs = pair_detections(scene, dets, m)
        for di, d in enumerate(dets):
            if d["model"] == m and (di not in pairs or
                                    scene["instances"][pairs[di]]["visible"] >= DONT_CARE_VISIBLE):
                n += 1
    return n


def div(a, b):
    return a / b if b > 0 else None


def pct(values, p):
    v = sorted(values)
    rank = p * (len(v) - 1)
    lo = int(math.floor(rank))
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (v[hi] - v[lo]) * (rank - lo)


def summarise(t):
    c = t["centers"]
    return {
        "object_precision": div(t["tp"], t["tp"] + t["fp"]),
        "object_recall": div(t["tp"], t["required"]),
        "pixel_precision": div(t["inter"], t["det"]),
        "pixel_recall": div(t["inter"], t["true"]),
        "center_mean_px": sum(c) / len(c) if c else None,
        "center_p95_px": pct(c, 0.95) if c else None,
        "points_mean_px": div(t["pt_sum"], t["pt_n"]),
        "pick_precision": div(t["safe"], t["flagged"]),
        "pick_recall": div(t["pick_found"], t["pick_req"]),
        "tp": t["tp"], "fp": t["fp"], "fn": t["required"] - t["tp"],
        "ms_per_frame": pct(t["ms"], 0.5) if t["ms"] else None,
    }


def score(ds, lines, only_method=None):
    index = {s["image"]: i for i, s in enumerate(ds["scenes"])}
    per_method = {}
    for line in lines:
        method = line["method"] or "detections"
        if only_method and method != only_method:
            continue
        if line["image"] not in index:
            raise FormatError("detections for '%s': no such scene in the dataset" % line["image"])
        per_method.setdefault(method, {})
        si = index[line["image"]]
        if si in per_method[method]:
            raise FormatError("detections for '%s' are listed twice" % line["image"])
        for d in line["instances"]:
            if d["model"] not in ds["models"]:
                raise FormatError("model '%s' is not one of the dataset's models" % d["model"])
        per_method[method][si] = line
    report = {"dataset": ds["name"], "methods": {}}
    centers = {}  # method -> {(scene, true instance): centre error}
    for method, by_scene in per_method.items():
        centers[method] = {}
        tallies = {m: new_tally() for m in ds["model_order"]}
        frame_ms = {}
        for si, scene in enumerate(ds["scenes"]):
            line = by_scene.get(si, {"instances": [], "ms": {}, "frame_ms": None})
            for m in ds["model_order"]:
                by_truth = {}
                score_scene(tallies[m], scene, line["instances"], m, by_truth)
                centers[method].update({(si, gi): e for gi, e in by_truth.items()})
            for m, ms in line["ms"].items():
                tallies[m]["ms"].append(ms)
                frame_ms[si] = frame_ms.get(si, 0.0) + ms
            if line["frame_ms"] is not None:
                frame_ms[si] = frame_ms.get(si, 0.0) + line["frame_ms"]
        pooled = new_tally()
        for t in tallies.values():
            for k, v in t.items():
                pooled[k] = pooled[k] + v
        pooled["ms"] = list(frame_ms.values())
        report["methods"][method] = {
            "overall": summarise(pooled),
            "models": {m: summarise(tallies[m]) for m in ds["model_order"]}}
        if ds["fps"] is not None:
            report["methods"][method]["tracking"] = score_tracking(ds, by_scene)
    if len(centers) > 1:
        # Centre errors on the same instances: those every method found.
        common = set.intersection(*(set(c) for c in centers.values()))
        report["paired_centers"] = {
            "instances": len(common),
            "center_mean_px": {m: sum(c[k] for k in common) / len(common) if common else None
                               for m, c in centers.items()}}
    return report


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dataset", help="dataset folder or its dataset.json")
    ap.add_argument("detections", help="detections JSON Lines file")
    ap.add_argument("--method", help="score only the lines of this method")
    args = ap.parse_args()
    try:
        report = score(load_dataset(args.dataset), load_detections(args.detections), args.method)
    except (FormatError, OSError) as e:
        print("score.py: %s" % e, file=sys.stderr)
        return 1
    json.dump(report, sys.stdout, indent=2)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
