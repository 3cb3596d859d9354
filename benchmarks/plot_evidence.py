#!/usr/bin/python3
"""Charts and tables from the evidence CSV (bench_evidence), deterministically.

    /usr/bin/python3 benchmarks/plot_evidence.py [docs/results/evidence.csv]

writes docs/figures/*.svg, docs/results/ablation.md and docs/results/summary.md (paths relative
to the repository root). Means are over seeds; stdlib + numpy + matplotlib (Agg) only.
"""
import csv
import math
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

plt.rcParams["svg.hashsalt"] = "vcar"  # deterministic ids in the SVG
plt.rcParams["svg.fonttype"] = "none"  # text stays text (smaller, diff-able)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RIGS = ["forward", "orbit", "sparse", "hemisphere"]
PEERS = ["naive", "sagd", "flashsplat", "gaussiancut", "ludvig", "lbg"]
VARIANTS = ["coarse", "sss", "abr", "full", "occlusion", "gapdir", "robust"]
ROBUST_ABLATION = ["robust-nor3", "robust-nolowpass", "robust-novalley", "robust-tau07", "robust-noundershoot",
                   "robust-nostrict", "robust-nosnap"]
TARGETS = ["sphere", "torus", "cylinder", "box"]
NUM = {"seed", "gaussians", "object_gaussians", "level", "width", "height", "n_train", "n_eval", "miou", "macc",
       "miou_01", "macc_01", "boundary_iou", "boundary_f1", "trimap_iou", "f1_3d", "precision_3d", "recall_3d",
       "selected", "t_render", "t_segment", "t_vote", "t_vca", "t_sss", "t_abr", "t_method", "time_s",
       "frames_segmented", "peak_mib", "peak_delta_mib", "n_coarse", "n_fine", "abr_flagged", "abr_compressed",
       "valid_cameras", "max_gap_deg", "sss_triggered"}


def load(path):
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            for k in NUM:
                r[k] = float(r[k]) if r.get(k, "") != "" else math.nan
            r["key"] = "vcar:" + r["variant"] if r["method"] == "vcar" else r["method"]
            r["target"] = r.get("target") or "seed"  # rows written before the column existed
            rows.append(r)
    return rows


def headline(rows):
    """The paper-suite rows: the seed's own target at 160 x 120 (the targets, diag, hires and donut sweeps
    have their own tables)."""
    return [r for r in rows if r["target"] == "seed" and r["width"] == 160]


def mean(xs):
    xs = [x for x in xs if not math.isnan(x)]
    return sum(xs) / len(xs) if xs else math.nan


def median(xs):
    xs = sorted(x for x in xs if not math.isnan(x))
    if not xs:
        return math.nan
    n = len(xs)
    return xs[n // 2] if n % 2 else 0.5 * (xs[n // 2 - 1] + xs[n // 2])


def group(rows, keys):
    g = defaultdict(list)
    for r in rows:
        g[tuple(r[k] for k in keys)].append(r)
    return g


def label(key):
    return {"vcar:full": "VCAR", "vcar:coarse": "VCAR coarse", "vcar:sss": "VCAR +SSS", "vcar:abr": "VCAR +ABR",
            "vcar:occlusion": "VCAR occl.", "vcar:gapdir": "VCAR gap-dir.", "vcar:robust": "vcar robust",
            "vcar:robust-band": "robust + band (R1)", "vcar:robust-noocc": "robust - fine occlusion (R3)",
            "vcar:robust-nor3": "robust - occlusion test (R3, and R10)",
            "vcar:robust-nokeep": "robust - keep unseen (R4)", "vcar:robust-nolowpass": "robust - ABR low-pass",
            "vcar:robust-novalley": "robust, tau_fine 0.8 (R14 off)", "vcar:robust-tau07": "robust, tau_fine 0.7 (before R6d)", "vcar:robust-nofs": "robust - foreshortening (R5)",
            "vcar:robust-noundershoot": "robust - undershoot band (R6)",
            "vcar:robust-nostrict": "robust - decisive threshold (R7)",
            "vcar:robust-noabru": "robust - undershoot ABR (R8)",
            "vcar:robust-coarse2": "robust + second coarse threshold (R9)",
            "vcar:robust-nocoplanar": "robust - hidden on a background plane (R10)",
            "vcar:robust-nogate": "robust - R6's gate (R6c)",
            "vcar:robust-noovershoot": "robust - R11 overshoot erosion",
            "vcar:robust-nogrow": "robust - R12 growth to occlusion edges",
            "vcar:robust-nosnap": "robust - snap to occlusion edges (R11-R12)"}.get(key, key)


STYLE = {}
_colours = plt.get_cmap("tab20").colors
for i, k in enumerate(PEERS + ["vcar:" + v for v in VARIANTS + ROBUST_ABLATION] + ["filtercluster"]):
    STYLE[k] = dict(color=_colours[i % len(_colours)], marker="os^vD<>ph*XP"[i % 12])
STYLE["vcar:full"] = dict(color="black", marker="*")  # the complete method stands out
STYLE["vcar:robust"] = dict(color="crimson", marker="*")  # vcar's default


def save(fig, name):
    out = os.path.join(ROOT, "docs", "figures", name)
    fig.savefig(out, format="svg", metadata={"Date": None}, bbox_inches="tight")
    plt.close(fig)
    return out


def pareto(points):
    """Points (t, acc): the front of lowest time for the highest accuracy, sorted by time."""
    front, best = [], -1.0
    for t, a in sorted(points):
        if a > best:
            front.append((t, a))
            best = a
    return front


def chart_pareto(rows, metric, name, ylabel):
    base = [r for r in headline(rows) if r["failure"] == "none" and not r["variant"].startswith("robust-")]
    fig, axes = plt.subplots(1, len(RIGS), figsize=(4.2 * len(RIGS), 3.8), sharey=True)
    for ax, rig in zip(axes, RIGS):
        pts = []
        for (key,), rs in sorted(group([r for r in base if r["rig"] == rig], ["key"]).items()):
            t, a = median(r["t_method"] for r in rs), mean(r[metric] for r in rs)  # time: median (shared cores)
            pts.append((t, a))
            ax.scatter([t], [a], label=label(key), s=36, **STYLE[key])
        f = pareto(pts)
        ax.step([p[0] for p in f], [p[1] for p in f], where="post", color="k", lw=0.8, ls="--")
        ax.set_xscale("log")
        ax.set_title(rig)
        ax.set_xlabel("time without segmenter (s, log)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(ylabel)
    axes[-1].legend(fontsize=7, loc="lower right")
    return save(fig, name)


SWEEP_X = {"dilate_diag": "dilation (% of the image diagonal)", "erode_diag": "erosion (% of the image diagonal)",
           "dilate": "dilation (px)", "erode": "erosion (px)", "blobs": "false-positive blobs per mask",
           "drop": "dropped-mask probability", "swap": "wrong-object probability", "jitter": "mask shift (px)",
           "views": "training views", "tau": "threshold tau (VCAR: tau_coarse = tau_fine)"}


def chart_sweep(rows, failure, metric="miou"):
    diag = failure.endswith("_diag")  # these run on every rig and start from the targets' clean runs
    pool = rows if diag else headline(rows)
    sw = [r for r in pool if r["failure"] == failure]
    if not sw:
        return None
    seeds = {r["seed"] for r in sw}
    methods = {r["key"] for r in sw}
    zero = [r for r in pool if r["failure"] == "none" and r["seed"] in seeds and r["key"] in methods and
            r["target"] == "seed" and r["width"] == 160] if failure not in ("views", "tau") else []
    rigs = [rig for rig in RIGS if any(r["rig"] == rig for r in sw)]
    fig, axes = plt.subplots(1, len(rigs), figsize=(4.6 * len(rigs), 3.6), sharey=True, squeeze=False)
    for ax, rig in zip(axes[0], rigs):
        keys = sorted({r["key"] for r in sw if r["rig"] == rig}, key=lambda k: (k.startswith("vcar"), k))
        for key in keys:
            pts = defaultdict(list)
            for r in sw + zero:
                if r["rig"] == rig and r["key"] == key:
                    pts[r["level"]].append(r[metric])
            xs = sorted(pts)
            ax.plot(xs, [mean(pts[x]) for x in xs], label=label(key), lw=2.2 if key in ("vcar:full", "vcar:robust") else 1.2,
                    ms=4, **STYLE[key])
        ax.set_title(rig)
        ax.set_xlabel(SWEEP_X.get(failure, failure))
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel({"miou": "mIoU (alpha > 0.5)"}.get(metric, metric))
    axes[0][-1].legend(fontsize=7)
    return save(fig, "stability_%s.svg" % failure)


def chart_size(rows):
    sz = [r for r in rows if r["failure"] == "size"]
    if not sz:
        return None
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(11, 4))
    # Repeated runs of one size (same seed) are summarised by their median time.
    for (key,), rs in sorted(group(sz, ["key"]).items()):
        by = group(rs, ["gaussians"])
        xs = sorted(k[0] for k in by)
        a0.plot(xs, [median(r["t_method"] for r in by[(x,)]) for x in xs], label=label(key), ms=4, **STYLE[key])
    a0.set_xscale("log"); a0.set_yscale("log")
    a0.set_xlabel("Gaussians in the scene (object fixed)"); a0.set_ylabel("time without segmenter (s)")
    a0.set_title("total cost vs scene size"); a0.grid(alpha=0.3); a0.legend(fontsize=7)
    by = group([r for r in sz if r["key"] == "vcar:robust"] or [r for r in sz if r["key"] == "vcar:full"], ["gaussians"])
    xs = sorted(k[0] for k in by)
    for col, lab in [] if not xs else [("t_render", "render (all frames)"), ("t_vote", "voting"), ("t_vca", "VCA"),
                     ("t_sss", "SSS (fine round)"), ("t_abr", "ABR")]:
        a1.plot(xs, [max(median(r[col] for r in by[(x,)]), 1e-5) for x in xs], marker="o", ms=4, label=lab)
    if xs:
        a1.set_xscale("log"); a1.set_yscale("log")
    a1.set_xlabel("Gaussians in the scene (object fixed)"); a1.set_ylabel("seconds")
    a1.set_title("vcar robust stages" if any(r["key"] == "vcar:robust" for r in sz) else "VCAR stages"); a1.grid(alpha=0.3); a1.legend(fontsize=7)
    return save(fig, "scaling.svg")


def fmt(x, d=3):
    return "-" if math.isnan(x) else ("%.*f" % (d, x))


def ablation_md(rows):
    base = [r for r in headline(rows) if r["failure"] == "none" and r["method"] == "vcar"]
    g = group(base, ["variant", "rig"])
    nseeds = len({r["seed"] for r in base})
    out = ["# VCAR ablation on the synthetic world", "",
           "Generated by `benchmarks/plot_evidence.py` from `docs/results/evidence.csv` (failure-free oracle, "
           "mean over %d seed(s); held-out views, rendered alpha > 0.5 vs the full silhouette). "
           "Shaped like the paper's Tables 3-4. Preset nvos on `forward`, lerf on the 360-degree rigs." % nseeds, ""]

    def table(variants, names, cols, title):
        out.append("### " + title)
        out.append("")
        out.append("| | " + " | ".join("%s %s" % (rig, c[1]) for rig in RIGS for c in cols) + " |")
        out.append("|---" * (1 + len(RIGS) * len(cols)) + "|")
        for v, n in zip(variants, names):
            cells = []
            for rig in RIGS:
                rs = g.get((v, rig), [])
                for c in cols:
                    cells.append(fmt(mean(r[c[0]] for r in rs)))
            out.append("| %s | %s |" % (n, " | ".join(cells)))
        out.append("")

    table(["coarse", "sss", "abr", "full"], ["coarse", "+SSS", "+ABR", "full (SSS + ABR)"],
          [("miou", "mIoU"), ("macc", "mAcc")], "mIoU / mAcc (alpha > 0.5)")
    table(["coarse", "sss", "abr", "full"], ["coarse", "+SSS", "+ABR", "full (SSS + ABR)"],
          [("boundary_iou", "bIoU"), ("f1_3d", "3D F1")], "Boundary IoU / 3D selection F1")
    table(["full", "occlusion", "gapdir", "robust"],
          ["full", "full + occlusion-aware", "full, gap-directed views", "robust (vcar's default)"],
          [("miou", "mIoU"), ("f1_3d", "3D F1")], "Beyond the paper")
    table(["robust"] + ROBUST_ABLATION, ["robust"] + [label("vcar:" + v) for v in ROBUST_ABLATION],
          [("miou", "mIoU"), ("boundary_iou", "bIoU"), ("f1_3d", "3D F1")],
          "The robust preset, one mechanism changed at a time (docs/robust.md)")
    # The same ablation under mask failures (the diag sweep; rigs where the ablation ran).
    d = [r for r in rows if r["failure"].endswith("_diag") and r["method"] == "vcar"]
    abl_rigs = sorted({r["rig"] for r in d if r["variant"].startswith("robust-")})
    if abl_rigs:
        d = [r for r in d if r["rig"] in abl_rigs]
        cases = sorted({(r["failure"], r["level"]) for r in d})
        gd = group(d, ["variant", "failure", "level"])
        out.append("### The robust ablation under mask failures (mean over %s and seeds)" % " and ".join(abl_rigs))
        out.append("")
        out.append("| | " + " | ".join("%s %g%% mIoU / 3D F1" % c for c in cases) + " |")
        out.append("|---" * (1 + len(cases)) + "|")
        for v in ["full", "robust"] + ROBUST_ABLATION:
            cells = []
            for c in cases:
                rs = gd.get((v,) + c, [])
                cells.append("%s / %s" % (fmt(mean(r["miou"] for r in rs)), fmt(mean(r["f1_3d"] for r in rs))))
            out.append("| %s | %s |" % ("paper (full)" if v == "full" else label("vcar:" + v), " | ".join(cells)))
        out.append("")
    path = os.path.join(ROOT, "docs", "results", "ablation.md")
    with open(path, "w") as f:
        f.write("\n".join(out))
    return path


def summary_md(rows):
    """Numbers for docs/results.md: the headline grid and the sweeps at each level."""
    out = ["# Evidence summary (generated)", ""]
    all_rows, rows = rows, headline(rows)
    base = [r for r in rows if r["failure"] == "none"]
    out += ["## Failure-free grid (accuracy: mean over seeds; t_method: median over seeds)", "",
            "| method | rig | mIoU | mAcc | mIoU@0.1 | bIoU | bF1 | 3D F1 | 3D prec | 3D rec | t_method s | frames |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for rig in RIGS:
        g = group([r for r in base if r["rig"] == rig], ["key"])
        for (key,), rs in sorted(g.items(), key=lambda kv: -mean(r["miou"] for r in kv[1])):
            out.append("| %s | %s | %s" % (label(key), rig, " | ".join(fmt(mean(r[c] for r in rs)) for c in
                       ["miou", "macc", "miou_01", "boundary_iou", "boundary_f1", "f1_3d", "precision_3d",
                        "recall_3d"]) + " | %s | %d |" % (fmt(median(r["t_method"] for r in rs)),
                                                     mean(r["frames_segmented"] for r in rs))))
    vc = [r for r in base if r["method"] == "vcar"]
    out += ["", "## VCAR diagnostics (failure-free, mean over seeds)", "",
            "| variant | rig | n_coarse | n_fine | object | ABR flagged | compressed | Delta_max deg | SSS ran |",
            "|---|---|---|---|---|---|---|---|---|"]
    for (v, rig), rs in sorted(group(vc, ["variant", "rig"]).items()):
        out.append("| %s | %s | %s |" % (v, rig, " | ".join(fmt(mean(r[c] for r in rs), 1) for c in
                   ["n_coarse", "n_fine", "object_gaussians", "abr_flagged", "abr_compressed", "max_gap_deg",
                    "sss_triggered"])))
    for failure in ["dilate", "erode", "blobs", "drop", "swap", "jitter", "views", "tau"]:
        sw = [r for r in rows if r["failure"] == failure]
        if not sw:
            continue
        levels = sorted({r["level"] for r in sw})
        out += ["", "## %s: mIoU by level" % SWEEP_X[failure], "",
                "| method | rig | " + " | ".join("%g" % l for l in levels) + " |",
                "|---|---|" + "---|" * len(levels)]
        for (key, rig), rs in sorted(group(sw, ["key", "rig"]).items()):
            by = group(rs, ["level"])
            out.append("| %s | %s | %s |" % (label(key), rig, " | ".join(
                fmt(mean(r["miou"] for r in by.get((l,), []))) for l in levels)))
    sz = [r for r in rows if r["failure"] == "size"]
    if sz:
        out += ["", "## Scene size (object fixed, forward rig): seconds without segmenter (median of repeated runs)", ""]
        sizes = sorted({r["gaussians"] for r in sz})
        out += ["| method | " + " | ".join("%d" % s for s in sizes) + " |", "|---|" + "---|" * len(sizes)]
        for (key,), rs in sorted(group(sz, ["key"]).items()):
            by = group(rs, ["gaussians"])
            out.append("| %s | %s |" % (label(key), " | ".join(fmt(median(r["t_method"] for r in by.get((s,), []))) for s in sizes)))
        for key in ["vcar:full", "vcar:robust"]:
            out += ["", "%s stages, median of repeated runs (s): render / vote / VCA / SSS / ABR; "
                    "n_coarse / mIoU / peak MiB" % label(key), ""]
            by = group([r for r in sz if r["key"] == key], ["gaussians"])
            for s in sizes:
                rs = by.get((s,), [])
                if not rs:
                    continue
                out.append("- %d: %s" % (s, " / ".join(fmt(median(r[c] for r in rs), 4) for c in
                           ["t_render", "t_vote", "t_vca", "t_sss", "t_abr"]) + "; %d / %s / %s (%d runs)" % (
                           median(r["n_coarse"] for r in rs), fmt(mean(r["miou"] for r in rs)),
                           fmt(median(r["peak_mib"] for r in rs), 0), len(rs))))
    out += beyond_md(all_rows)
    path = os.path.join(ROOT, "docs", "results", "summary.md")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
    return path


def beyond_md(rows):
    """Tables of the sweeps beyond the paper's suite: every target shape, failures by share of the diagonal,
    >= 640 px images and trained Gaussians; each with vcar robust, the paper's VCAR and the best peer."""
    out = []
    peers = set(PEERS + ["filtercluster"])

    def block(title, rs, cols):
        out.extend(["", "## " + title, "",
                    "| case | rig | robust mIoU / bIoU / 3D F1 | paper (full) | best peer by mIoU | robust / paper t_method |",
                    "|---|---|---|---|---|---|"])
        for case_key, cases in sorted(group(rs, cols + ["rig"]).items(),
                                      key=lambda kv: (kv[0][:-1], RIGS.index(kv[0][-1]) if kv[0][-1] in RIGS else 9)):
            g = group(cases, ["key"])
            def trio(k):
                c = g.get((k,), [])
                return "%s / %s / %s" % tuple(fmt(mean(r[m] for r in c)) for m in ["miou", "boundary_iou", "f1_3d"]) if c else "-"
            best = max(((mean(r["miou"] for r in v), k[0]) for k, v in g.items() if k[0] in peers), default=None)
            ratio = math.nan
            if g.get(("vcar:robust",)) and g.get(("vcar:full",)):
                ratio = median(r["t_method"] for r in g[("vcar:robust",)]) / median(r["t_method"] for r in g[("vcar:full",)])
            out.append("| %s | %s | %s | %s | %s | %s |" % (" ".join(str(x) if not isinstance(x, float) else "%g" % x for x in case_key[:-1]),
                       case_key[-1], trio("vcar:robust"), trio("vcar:full"),
                       "%s %s" % (best[1], fmt(best[0])) if best else "-", fmt(ratio, 2)))

    # Cost: robust against the paper's preset in the same experiment (same world, masks and process).
    pair = group([r for r in rows if r["key"] in ("vcar:full", "vcar:robust")],
                 ["seed", "rig", "failure", "level", "target", "width", "gaussians", "n_train"])
    ratios = sorted(median(r["t_method"] for r in v if r["key"] == "vcar:robust") /
                    median(r["t_method"] for r in v if r["key"] == "vcar:full")
                    for v in pair.values() if {r["key"] for r in v} == {"vcar:full", "vcar:robust"})
    if ratios:
        q = lambda f: ratios[min(len(ratios) - 1, int(f * len(ratios)))]
        out.extend(["", "## Cost of the robust preset", "",
                    "t_method (no segmenter) of vcar robust / VCAR (paper) in the same experiment, %d experiments: "
                    "median %s, quartiles %s-%s, 90th percentile %s." % (len(ratios), fmt(q(0.5), 2), fmt(q(0.25), 2),
                                                                         fmt(q(0.75), 2), fmt(q(0.9), 2))])
    t = [r for r in rows if r["failure"] == "none" and r["target"] in TARGETS and r["width"] == 160]
    if t:
        block("Every target shape (160 x 120, failure-free; mean over seeds)", t, ["target"])
    d = [r for r in rows if r["failure"].endswith("_diag")]
    if d:
        block("Masks eroded / dilated by a share of the image diagonal (%, 160 x 120)", d, ["failure", "level"])
    h = [r for r in rows if r["width"] >= 640]
    if h:
        block("640 x 480 images (failure-free)", h, ["target"])
    n = [r for r in rows if r["target"] == "donut"]
    if n:
        block("Trained Gaussians (tests/data/donut.ply copies, 256 x 192; erode level in px)", n, ["failure", "level"])
    return out


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "results", "evidence.csv")
    rows = load(path)
    os.makedirs(os.path.join(ROOT, "docs", "figures"), exist_ok=True)
    os.makedirs(os.path.join(ROOT, "docs", "results"), exist_ok=True)
    written = [chart_pareto(rows, "miou", "time_vs_miou.svg", "mIoU (alpha > 0.5)"),
               chart_pareto(rows, "boundary_iou", "time_vs_boundary_iou.svg", "boundary IoU")]
    for failure in ["dilate", "erode", "blobs", "drop", "swap", "jitter", "views", "tau", "erode_diag", "dilate_diag"]:
        written.append(chart_sweep(rows, failure))
    written += [chart_size(rows), ablation_md(rows), summary_md(rows)]
    for w in written:
        if w:
            print(os.path.relpath(w, ROOT))


if __name__ == "__main__":
    main()
