#!/usr/bin/python3
"""Several objects in one `vcar segment --prompts` run against one `vcar segment` run per object,
end to end through the command line with an external segmenter program (docs/cli.md), on a
synthetic capture (`vcar synth`). What an external segmenter costs per request (a process start,
reading the frames, for SAM 2 loading its model) is paid once per request: one run of two
objects makes two requests (the shared coarse round, the batched fine rounds), two single runs
make four. Wall-clock medians of interleaved repeats, measured in the same run.

    bench_multi_object_cli.py VCAR_BINARY [--repeats 3] [--sleep 0,2] [--work DIR]

--sleep: colour_picker.py waits this many seconds at the start of each request (0: the program
as it is; 2: standing in for a model that takes 2 s to load, e.g. SAM 2 on a GPU).
Prompts: the target and again the target (prompts_twice, as the CLI tests), so both objects'
rounds are the same size; the first object's selection must equal the single run's.
"""
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
PICKER = os.path.join(HERE, "..", "examples", "segmenters", "colour_picker.py")


def run(cmd):
    t = time.monotonic()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return time.monotonic() - t


def main(argv):
    args = argv[1:]
    if not args:
        print(__doc__, file=sys.stderr)
        return 64
    vcar = os.path.abspath(args.pop(0))
    repeats, sleeps, work = 3, [0.0, 2.0], None
    while args:
        a = args.pop(0)
        if a == "--repeats":
            repeats = int(args.pop(0))
        elif a == "--sleep":
            sleeps = [float(s) for s in args.pop(0).split(",")]
        elif a == "--work":
            work = args.pop(0)
        else:
            print("unknown option " + a, file=sys.stderr)
            return 64
    work = work or tempfile.mkdtemp(prefix="vcar-bench-multi-")
    ds = os.path.join(work, "dataset")
    shutil.rmtree(ds, ignore_errors=True)
    subprocess.run([vcar, "synth", "--rig", "forward", "--seed", "1", "--gaussians", "20000", "--views", "12",
                    "--width", "160", "--height", "120", "--out", ds], check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(ds, "prompt.json")) as f:
        prompt = json.load(f)
    ref, point = prompt["reference_view"], prompt["points"][0]
    prompts = os.path.join(work, "prompts.json")
    with open(prompts, "w") as f:
        json.dump([{"name": n, "reference_view": ref, "points": [point]} for n in ("target", "again")], f)
    common = [vcar, "-q", "segment", "--scene", os.path.join(ds, "scene.ply"), "--cameras", os.path.join(ds, "cameras.json")]
    print("bench_multi_object_cli: %s, 20000 Gaussians, 12 views at 160x120 (forward), robust preset, median of %d"
          % (os.path.basename(vcar), repeats))
    for sleep in sleeps:
        seg = "/usr/bin/python3 %s --sleep %g" % (PICKER, sleep)
        singles, multis = [], []
        for r in range(repeats):
            t = 0.0
            for k in range(2):
                out = os.path.join(work, "single%d" % k)
                shutil.rmtree(out, ignore_errors=True)
                t += run(common + ["--prompt-view", ref, "--points", "%g,%g" % tuple(point), "--segmenter-cmd", seg,
                                   "--out", out])
            singles.append(t)
            out = os.path.join(work, "multi")
            shutil.rmtree(out, ignore_errors=True)
            multis.append(run(common + ["--prompts", prompts, "--segmenter-cmd", seg, "--out", out]))
        with open(os.path.join(work, "single0", "report.json")) as f:
            single = json.load(f)
        with open(os.path.join(work, "multi", "report.json")) as f:
            multi = json.load(f)
        with open(os.path.join(work, "single0", "selection.json")) as f:
            a = json.load(f)["indices"]
        with open(os.path.join(work, "multi", "selection.json")) as f:
            b = json.load(f)["objects"][0]["indices"]
        ts, tm = statistics.median(singles), statistics.median(multis)
        print("segmenter start-up %.0f s: two single runs %.2f s, one run of two objects %.2f s: ratio %.2f "
              "(minima %.2f s, %.2f s: %.2f); segmenter requests 4 vs %d; SSS %s; first object %s the single run"
              % (sleep, ts, tm, tm / ts, min(singles), min(multis), min(multis) / min(singles),
                 multi["segmenter_calls"], "ran" if single["sss_triggered"] else "not needed",
                 "equals" if a == b else "DIFFERS from"))
        if a != b:
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
