#!/usr/bin/env python3
"""Tables of docs/hard-sets.md: per set and method, pickdetect-eval's figures (from
OUT/results/SET.json) and what the errors are (from OUT/results/SET.jsonl against the truth).

usage: hard-sets-errors.py OUT SET...

The kinds of error, a description beside the scorer's counts: detections are paired with true
instances of their model as the scorer pairs them (greedily by IoU, at least 0.5, the convex
hull of a detection's outline); a false detection is a *duplicate* when it overlaps (IoU >= 0.2)
a box that another detection found (*flipped* when turned by more than 90 degrees from it),
*spanning* when it covers at least a fifth of each of two true boxes, *shifted* when it
overlaps one box (IoU 0.1-0.5: a copy along a row or a bundle, or a pose off the box), *other
model* when it lies on a box of another model (IoU >= 0.5 with it: another face or look-alike),
and a *ghost* otherwise. A required instance left unpaired is *missed*, and counted again in
brackets when something lies on it (covered >= 0.02).
"""
import json
import math
import sys


def direction(points):
    return math.atan2(points[2][1] - points[1][1], points[2][0] - points[1][0])


def area(polygon):
    return abs(sum(x1 * y2 - x2 * y1 for (x1, y1), (x2, y2) in
                   zip(polygon, polygon[1:] + polygon[:1]))) / 2


def hull(points):
    pts = sorted(map(tuple, points))
    if len(pts) < 3:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def clip(subject, convex):
    """Sutherland-Hodgman: subject within the convex polygon (counter-clockwise)."""
    out = subject
    for (ax, ay), (bx, by) in zip(convex, convex[1:] + convex[:1]):
        if not out:
            break
        inp, out = out, []

        def side(p):
            return (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax)

        for p, q in zip(inp, inp[1:] + inp[:1]):
            sp, sq = side(p), side(q)
            if sp >= 0:
                out.append(p)
            if (sp >= 0) != (sq >= 0):
                t = sp / (sp - sq)
                out.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return out


def overlap(a, b, frame):
    """Intersection area of two outlines (their convex hulls) within the frame."""
    return area(clip(clip(hull(a), hull(b)), frame))


def kinds(dataset, lines, method):
    scenes = {s["image"]: s for s in dataset["scenes"]}
    out = dict(duplicate=0, flipped=0, spanning=0, shifted=0, other=0, ghost=0, missed=0,
               missed_covered=0)
    for line in lines:
        if line.get("method", method) != method:
            continue
        scene = scenes[line["image"]]
        truth = scene["instances"]
        w, h = scene["width"], scene["height"]
        frame = hull([(0, 0), (w, 0), (w, h), (0, h)])
        seen = [area(clip(hull(t["polygon"]), frame)) for t in truth]
        dets = line["instances"]
        inter = [[overlap(d["polygon"], t["polygon"], frame) if d["model"] == t["model"] else 0.0
                  for t in truth] for d in dets]
        iou = [[inter[i][k] / (area(clip(hull(d["polygon"]), frame)) + seen[k] - inter[i][k])
                if inter[i][k] > 0 else 0.0 for k in range(len(truth))]
               for i, d in enumerate(dets)]

        def iou_of(d, k):
            both = overlap(d["polygon"], truth[k]["polygon"], frame)
            return both / (area(clip(hull(d["polygon"]), frame)) + seen[k] - both)

        pairs = sorted(((iou[i][k], i, k) for i in range(len(dets)) for k in range(len(truth))
                        if iou[i][k] >= 0.5), key=lambda p: (-p[0], p[1], p[2]))
        det_of, truth_of = {}, {}
        for _, i, k in pairs:
            if i not in det_of and k not in truth_of:
                det_of[i], truth_of[k] = k, i
        for i, d in enumerate(dets):
            if i in det_of:
                continue
            found = [k for k in truth_of if iou[i][k] >= 0.2]
            if found:
                t = truth[found[0]]
                turn = abs(direction(d["points"]) - direction(t["points"]))
                turn = min(turn, 2 * math.pi - turn)
                out["flipped" if turn > math.pi / 2 else "duplicate"] += 1
            elif sum(inter[i][k] >= 0.2 * seen[k] > 0 for k in range(len(truth))) >= 2:
                out["spanning"] += 1
            elif any(v >= 0.1 for v in iou[i]):
                out["shifted"] += 1
            elif any(t["model"] != d["model"] and iou_of(d, k) >= 0.5
                     for k, t in enumerate(truth)):
                out["other"] += 1
            else:
                out["ghost"] += 1
        for k, t in enumerate(truth):
            if t["visible"] >= 0.3 and k not in truth_of:
                out["missed"] += 1
                out["missed_covered"] += t.get("covered", 0) >= 0.02
    return out


def pct(v):
    return "-" if v is None else f"{100 * v:.1f}"


def main():
    root, sets = sys.argv[1], sys.argv[2:]
    for name in sets:
        dataset = json.load(open(f"{root}/{name}/dataset.json"))
        summary = json.load(open(f"{root}/results/{name}.json"))["methods"]
        lines = [json.loads(l) for l in open(f"{root}/results/{name}.jsonl")]
        required = sum(t["visible"] >= 0.3 for s in dataset["scenes"] for t in s["instances"])
        print(f"\n`{name}`: {len(dataset['scenes'])} scenes, {required} required instances, "
              f"models {', '.join(dataset['models'])}\n")
        print("| method | obj P | obj R | centre px | pick P | pick R | TP | FP | FN "
              "| dup | flipped | spanning | shifted | other model | ghost | missed (covered) |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for method in ("voting", "ransac-clustered", "ransac-all"):
            o = summary[method]["overall"]
            k = kinds(dataset, lines, method)
            centre = "-" if o["center_mean_px"] is None else f"{o['center_mean_px']:.2f}"
            print(f"| {method} | {pct(o['object_precision'])} | {pct(o['object_recall'])} | "
                  f"{centre} | {pct(o['pick_precision'])} | {pct(o['pick_recall'])} | {o['tp']} | "
                  f"{o['fp']} | {o['fn']} | {k['duplicate']} | {k['flipped']} | {k['spanning']} | "
                  f"{k['shifted']} | {k['other']} | "
                  f"{k['ghost']} | {k['missed']} ({k['missed_covered']}) |")


if __name__ == "__main__":
    main()
