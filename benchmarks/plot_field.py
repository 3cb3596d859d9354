#!/usr/bin/python3
"""Tables and charts of the field (bench_field), deterministically.

    /usr/bin/python3 benchmarks/plot_field.py [docs/results/field.csv]
    /usr/bin/python3 benchmarks/plot_field.py --merge OUT.csv IN.csv [IN.csv ...]   (parts of a run)

writes docs/results/field.md, docs/figures/field_f1_vs_time.svg and
docs/figures/field_miou_vs_time.svg (paths relative to the repository root). Means are over the
cases (seed x target) of a role; times are medians (the runs shared 2 cores with other work).
stdlib + matplotlib (Agg) only.
"""
import csv
import math
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

plt.rcParams["svg.hashsalt"] = "vcar"  # deterministic ids in the SVG
plt.rcParams["svg.fonttype"] = "none"  # text stays text (smaller, diff-able)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PEERS = ["naive", "sagd", "flashsplat", "gaussiancut", "ludvig", "lbg"]
METHODS = ["vcar:paper", "vcar:robust", "vcar:code", "vcar:lean"] + PEERS
SEGMENTERS = ["grabcut", "isnet", "oracle", "oracle-sam-nodrift", "oracle-sam", "exact"]
# The rig as the tables name it: its kind, with the image size where it is not the field's 640 x 480
# (run_field.sh's hires part: the forward rig at 1008 x 756).
RIGS = ["forward", "forward 1008x756", "orbit", "sparse"]
NUM = {"seed", "gaussians", "object_gaussians", "width", "height", "n_train", "n_eval", "miou", "macc", "miou_01",
       "boundary_iou", "boundary_f1", "f1_3d", "precision_3d", "recall_3d", "selected", "t_render", "t_segment",
       "t_method", "time_s", "frames_segmented", "n_coarse", "n_fine", "mask_iou", "mask_none", "mask_frames", "t_own"}
LABEL = {"vcar:paper": "VCAR, paper preset", "vcar:robust": "vcar default (robust)",
         "vcar:code": "VCAR, released code's preset", "vcar:lean": "VCAR paper preset + R3 + R13 (issue 47)"}
SEG_LABEL = {"grabcut": "GrabCut", "isnet": "ISNet", "oracle": "oracle (rendered)",
             "oracle-sam-nodrift": "oracle + SAM-like failures, no drift",
             "oracle-sam": "oracle + SAM-like failures with drift",
             "exact": "exact masks (the target alone in the fine round)"}


def load(path):
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            for k in NUM:
                r[k] = float(r[k]) if r.get(k, "") != "" else math.nan
            r["key"] = "vcar:" + r["variant"] if r["method"] == "vcar" else r["method"]
            w, h = r.get("width", 640), r.get("height", 480)
            if (float(w), float(h)) != (640.0, 480.0):
                r["rig"] = "%s %dx%d" % (r["rig"], float(w), float(h))
            rows.append(r)
    return rows


def mean(xs):
    xs = [x for x in xs if not math.isnan(x)]
    return sum(xs) / len(xs) if xs else math.nan


def median(xs):
    xs = sorted(x for x in xs if not math.isnan(x))
    if not xs:
        return math.nan
    n = len(xs)
    return xs[n // 2] if n % 2 else 0.5 * (xs[n // 2 - 1] + xs[n // 2])


def fmt(x, d=3):
    return "-" if math.isnan(x) else ("%.*f" % (d, x))


def secs(x):
    return "-" if math.isnan(x) else ("%.0f" % x if x >= 10 else "%.1f" % x)


def group(rows, keys):
    g = defaultdict(list)
    for r in rows:
        g[tuple(r[k] for k in keys)].append(r)
    return g


def label(key):
    return LABEL.get(key, key)


def preset_of(rows):
    """The paper preset's name(s) in these rows (nvos forward-facing, lerf 360)."""
    return "/".join(sorted({r["preset"] for r in rows if r["key"] == "vcar:paper"}))


def cells(rows):
    """(segmenter, rig) pairs present, in table order."""
    have = {(r["segmenter"], r["rig"]) for r in rows}
    return [(s, g) for s in SEGMENTERS for g in RIGS if (s, g) in have]


def methods(rows):
    have = {r["key"] for r in rows}
    return [m for m in METHODS if m in have]


def masks_2d(rows):
    """The segmenter's coarse-round masks (one set per case, shared by the case's runs): mean 2D
    IoU over the cases, frames answered 'no mask' of all frames."""
    case = {}
    for r in rows:
        case[(r["seed"], r["target"])] = r
    iou = mean(r["mask_iou"] for r in case.values())
    none = sum(r["mask_none"] for r in case.values())
    frames = sum(r["mask_frames"] for r in case.values())
    return iou, int(none), int(frames)


def means_table(rows):
    out = ["| segmenter | rig | masks' 2D IoU (no mask) | method | cases | 3D F1 | worst 3D F1 | precision | recall "
           "| mIoU | boundary IoU | time (s) | without segmenter (s) |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for seg, rig in cells(rows):
        rs = [r for r in rows if r["segmenter"] == seg and r["rig"] == rig]
        iou, none, frames = masks_2d(rs)
        first = True
        by = group(rs, ["key"])
        best_peer = max((m for m in methods(rs) if m in PEERS), key=lambda m: mean(r["f1_3d"] for r in by[(m,)]),
                        default=None)
        for m in methods(rs):
            g = by[(m,)]
            name = label(m) + (" (%s)" % preset_of(g) if m == "vcar:paper" else "")
            if m == best_peer:
                name += " (best peer)"
            out.append("| %s | %s | %s | %s | %d | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                SEG_LABEL[seg] if first else "", rig if first else "",
                ("%s (%d of %d)" % (fmt(iou), none, frames)) if first else "", name, len(g),
                fmt(mean(r["f1_3d"] for r in g)), fmt(min(r["f1_3d"] for r in g)),
                fmt(mean(r["precision_3d"] for r in g)), fmt(mean(r["recall_3d"] for r in g)),
                fmt(mean(r["miou"] for r in g)), fmt(mean(r["boundary_iou"] for r in g)),
                secs(median(r["time_s"] for r in g)), secs(median(r["t_method"] for r in g))))
            first = False
    return out


def targets_table(rows):
    """Per target: 3D F1 / mIoU of each method, under the segmenter's masks' 2D IoU."""
    targets = sorted({r["target"] for r in rows}, key=lambda t: ["biker", "guitar", "donut"].index(t)
                     if t in ("biker", "guitar", "donut") else 9)
    out = ["| segmenter | rig | method | " + " | ".join(targets) + " |", "|---|---|---|" + "---|" * len(targets)]
    for seg, rig in cells(rows):
        rs = [r for r in rows if r["segmenter"] == seg and r["rig"] == rig]
        cols = [fmt(masks_2d([r for r in rs if r["target"] == t])[0]) for t in targets]
        out.append("| %s | %s | *its masks' 2D IoU* | %s |" % (SEG_LABEL[seg], rig, " | ".join(cols)))
        for m in methods(rs):
            cols = []
            for t in targets:
                g = [r for r in rs if r["key"] == m and r["target"] == t]
                cols.append("%s / %s" % (fmt(mean(r["f1_3d"] for r in g)), fmt(mean(r["miou"] for r in g))) if g else "-")
            out.append("|  |  | %s | %s |" % (label(m), " | ".join(cols)))
    return out


def versus_paper(rows, key="vcar:robust"):
    """Per case: 3D F1 of `key` (the default, or issue 47's candidate) against the paper preset's."""
    seeds = sorted({int(r["seed"]) for r in rows})
    out = ["| segmenter | rig | target | " + " | ".join("seed %d" % s for s in seeds) + " | below paper by > 0.005 |",
           "|---|---|---|" + "---|" * len(seeds) + "---|"]
    for seg, rig in cells(rows):
        rs = [r for r in rows if r["segmenter"] == seg and r["rig"] == rig]
        if not {"vcar:paper", key} <= {r["key"] for r in rs}:
            continue
        first = True
        for t in ["biker", "guitar", "donut"]:
            cols, worse = [], 0
            for s in seeds:
                d = {r["key"]: r["f1_3d"] for r in rs if r["target"] == t and int(r["seed"]) == s}
                if "vcar:paper" in d and key in d:
                    delta = d[key] - d["vcar:paper"]
                    worse += delta < -0.005
                    cols.append("%s / %s (%+.3f)" % (fmt(d[key]), fmt(d["vcar:paper"]), delta))
                else:
                    cols.append("-")
            out.append("| %s | %s | %s | %s | %d |" % (SEG_LABEL[seg] if first else "", rig if first else "", t,
                                                       " | ".join(cols), worse))
            first = False
    return out


def paired(rows, key):
    """(paper row, `key` row) of every case (segmenter, rig, seed, target) that has both."""
    by = group(rows, ["segmenter", "rig", "seed", "target"])
    out = []
    for k in sorted(by):
        d = {r["key"]: r for r in by[k]}
        if "vcar:paper" in d and key in d:
            out.append((d["vcar:paper"], d[key]))
    return out


def bars_table(rows):
    """Issue 47's bars, per cell, for the default and the candidate: the cases more than 0.005
    3D F1 below the paper preset, the worst difference, the worst case's 3D F1, and the own time
    (t_own: everything but renders and the segmenter) against the paper preset's in the same run
    (median of the per-case ratios)."""
    out = ["| segmenter | rig | method | cases | below paper by > 0.005 | worst difference | worst 3D F1 "
           "| own time / paper's (median) | own time, median (s) |", "|---|---|---|---|---|---|---|---|---|"]
    for seg, rig in cells(rows):
        rs = [r for r in rows if r["segmenter"] == seg and r["rig"] == rig]
        first = True
        for key in ["vcar:robust", "vcar:lean"]:
            pairs = paired(rs, key)
            if not pairs:
                continue
            delta = [b["f1_3d"] - a["f1_3d"] for a, b in pairs]
            ratio = [b["t_own"] / a["t_own"] for a, b in pairs if a["t_own"] > 0]
            out.append("| %s | %s | %s | %d | %d | %+.3f | %s | %s | %s |" % (
                SEG_LABEL[seg] if first else "", rig if first else "", label(key), len(pairs),
                sum(d < -0.005 for d in delta), min(delta), fmt(min(b["f1_3d"] for _, b in pairs)),
                fmt(median(ratio), 2), secs(median(b["t_own"] for _, b in pairs))))
            first = False
    return out


STYLE = {}
_colours = plt.get_cmap("tab10").colors
for i, k in enumerate(PEERS):
    STYLE[k] = dict(color=_colours[i % len(_colours)], marker="os^vD<>ph*"[i])
STYLE["vcar:paper"] = dict(color="black", marker="*")
STYLE["vcar:robust"] = dict(color="crimson", marker="*")
STYLE["vcar:code"] = dict(color="grey", marker="P")
STYLE["vcar:lean"] = dict(color="darkorange", marker="X")


def chart(rows, metric, name, ylabel):
    """Held-out means against the median time of a run (segmenter included, log scale), one panel
    per segmenter x rig; the thin bar spans the worst and best case. A mean far below the others
    (lbg's) is drawn at the panel's floor, with its value."""
    cs = cells(rows)
    if not cs:
        return None
    pts = []  # (panel, method, time, mean, worst, best)
    for i, (seg, rig) in enumerate(cs):
        rs = [r for r in rows if r["segmenter"] == seg and r["rig"] == rig]
        for m in methods(rs):
            vals = [r[metric] for r in rs if r["key"] == m]
            pts.append((i, m, median(r["time_s"] for r in rs if r["key"] == m), mean(vals), min(vals), max(vals)))
    floor = max(0.0, min([p[4] for p in pts if p[3] >= 0.5] or [0.0]) - 0.03)
    ncol = min(4, len(cs))
    nrow = (len(cs) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.9 * nrow), sharey=True, squeeze=False)
    for i in range(len(cs), nrow * ncol):
        axes[i // ncol][i % ncol].set_visible(False)
    handles = {}
    for i, (seg, rig) in enumerate(cs):
        ax = axes[i // ncol][i % ncol]
        for _, m, t, mu, lo, hi in [p for p in pts if p[0] == i]:
            if mu < floor:
                ax.scatter([t], [floor + 0.004], s=36, zorder=3, color=STYLE[m]["color"], marker="v")
                ax.annotate("%s %s" % (m, fmt(mu)), (t, floor + 0.004), textcoords="offset points", xytext=(0, 6),
                            ha="center", fontsize=7, color=STYLE[m]["color"])
                continue
            ax.plot([t, t], [max(lo, floor), hi], color=STYLE[m]["color"], lw=0.8, alpha=0.5)
            handles[m] = ax.scatter([t], [mu], s=70 if m.startswith("vcar") else 36, zorder=3, **STYLE[m])
        ax.set_xscale("log")
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda x, _: "%g" % x))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.FuncFormatter(lambda x, _: "%g" % x if str(int(x))[0] in "25" else ""))
        ax.tick_params(axis="x", which="minor", labelsize=7)
        iou, _, _ = masks_2d([r for r in rows if r["segmenter"] == seg and r["rig"] == rig])
        ax.set_title("%s, %s\n(masks' 2D IoU %s)" % (SEG_LABEL[seg], rig, fmt(iou)), fontsize=9)
        ax.set_xlabel("time per run, segmenter included (s, log)", fontsize=8)
        ax.grid(alpha=0.3, which="both")
    for row in axes:
        row[0].set_ylabel(ylabel)
    axes[0][0].set_ylim(bottom=floor)
    order = [m for m in METHODS if m in handles]
    fig.legend([handles[m] for m in order], [label(m) for m in order], loc="lower center", ncol=len(order),
               fontsize=8, bbox_to_anchor=(0.5, -0.06 / nrow), frameon=False)
    out = os.path.join(ROOT, "docs", "figures", name)
    fig.savefig(out, format="svg", metadata={"Date": None}, bbox_inches="tight")
    plt.close(fig)
    return out


def field_md(rows, path):
    held = [r for r in rows if r["role"] == "heldout"]
    tune = [r for r in rows if r["role"] == "tuning"]
    other = [r for r in rows if r["role"] not in ("heldout", "tuning")]
    w, h = sorted({(int(r["width"]), int(r["height"])) for r in rows})[0]
    lines = ["# The field: tables", "",
             "Generated by `benchmarks/plot_field.py` from `%s` (%d runs; `benchmarks/bench_field.cpp`). "
             "Stage `%s`, %dx%d. Means over the cases (seed x target) of each role; worst = the lowest case; "
             "times are medians of a run's seconds with its segmenter (the coarse round's masks counted in every "
             "run that uses them) and without. The masks' 2D IoU: the segmenter's coarse-round masks against the "
             "target's visible ground truth of each training view, mean over the views with a mask (in brackets: "
             "the views answered \"no mask\" of all). docs/results.md (\"Field\") says how it was run and what it shows."
             % (os.path.relpath(path, ROOT), len(rows), rows[0]["stage"] if rows else "-", w, h), ""]
    if held:
        seeds = sorted({int(r["seed"]) for r in held})
        lines += ["## Held-out seeds (%s): means" % ", ".join(map(str, seeds)), ""] + means_table(held) + [""]
        lines += ["## Held-out seeds: per target", "", "3D F1 / mIoU, means over the held-out seeds.", ""] + targets_table(held) + [""]
        lines += ["## Held-out seeds: issue 47's bars",
                  "", "The default (robust) and the candidate (paper preset + R3 + R13) against the paper preset, "
                  "case by case (a case: segmenter, rig, seed, target).", ""] + bars_table(held) + [""]
        lines += ["## Held-out seeds: the default against the paper preset, per case",
                  "", "3D F1 of the default (robust) / of the paper preset (difference).", ""] + versus_paper(held) + [""]
        if any(r["key"] == "vcar:lean" for r in held):
            lines += ["## Held-out seeds: the candidate (paper preset + R3 + R13) against the paper preset, per case",
                      "", "3D F1 of the candidate / of the paper preset (difference).", ""] + versus_paper(held, "vcar:lean") + [""]
    if tune:
        seeds = sorted({int(r["seed"]) for r in tune})
        lines += ["## Tuning seeds (%s): means" % ", ".join(map(str, seeds)), "",
                  "The seeds the default may be tuned on: not evidence of how it generalises.", ""] + means_table(tune) + [""]
        lines += ["## Tuning seeds: per target", "", "3D F1 / mIoU, means over the tuning seeds.", ""] + targets_table(tune) + [""]
        lines += ["## Tuning seeds: the default against the paper preset, per case", ""] + versus_paper(tune) + [""]
    if other:
        lines += ["## Other seeds: means", ""] + means_table(other) + [""]
    out = os.path.join(ROOT, "docs", "results", "field.md")
    with open(out, "w") as f:
        f.write("\n".join(lines))
    return out


def merge(out, inputs):
    """Concatenates bench_field CSVs (parts of one field run) into `out`; their headers must match,
    and no (method, variant, rig, width, height, segmenter, seed, target) may come twice."""
    header, rows, seen = None, [], set()
    for path in inputs:
        with open(path, newline="") as f:
            r = csv.reader(f)
            h = next(r)
            if header is None:
                header = h
            elif h != header:
                sys.exit("plot_field: %s: its columns differ from %s's" % (path, inputs[0]))
            key = [h.index(k) for k in ("method", "variant", "rig", "width", "height", "segmenter", "seed", "target")]
            for row in r:
                k = tuple(row[i] for i in key)
                if k in seen:
                    sys.exit("plot_field: %s: run %s comes twice" % (path, ",".join(k)))
                seen.add(k)
                rows.append(row)
    with open(out, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)
    print("%s: %d runs from %d files" % (out, len(rows), len(inputs)))


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--merge":
        if len(sys.argv) < 4:
            sys.exit("usage: plot_field.py --merge OUT.csv IN.csv [IN.csv ...]")
        merge(sys.argv[2], sys.argv[3:])
        return
    path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "results", "field.csv")
    rows = load(path)
    os.makedirs(os.path.join(ROOT, "docs", "figures"), exist_ok=True)
    os.makedirs(os.path.join(ROOT, "docs", "results"), exist_ok=True)
    held = [r for r in rows if r["role"] == "heldout"] or rows  # the charts: held-out seeds
    written = [chart(held, "f1_3d", "field_f1_vs_time.svg", "3D F1"),
               chart(held, "miou", "field_miou_vs_time.svg", "held-out mIoU (alpha > 0.5)"),
               field_md(rows, os.path.abspath(path))]
    for w in written:
        if w:
            print(os.path.relpath(w, ROOT))


if __name__ == "__main__":
    main()
