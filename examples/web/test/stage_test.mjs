// The page on a stage of real trained objects (vcar synth --stage: biker, guitar and donut on a
// floor, every Gaussian labelled), in Debian's headless Chromium, against the stage's labels and
// the native twin (docs/web.md, "The stage test").
//
//   node test/stage_test.mjs --native BUILD/vcar_web_native --vcar BUILD/vcar \
//        (--dataset DIR | --stage ../stages/three_objects.json --seed 1 [--synth-args "--views 8"]) \
//        [--prompt click|box] [--segmenter grabcut|region] [--quality full|fast] [--max-side N]
//        [--min-iou 0.98]
//        [--min-f1 biker=0.9,guitar=0.8] [--spz ../../../shared/data/biker.spz] [--timeout 600]
// --dataset: a `vcar synth --stage` dataset; without it, `vcar synth --stage --seed` (with
// --synth-args, e.g. "--views 8 --width 320 --height 240") writes one into a temporary folder
// (removed at the end).
//
// For each object of the dataset's prompt.json that has a prompt, on its reference view: a click
// on its first positive point (--prompt click, the default) or its box (--prompt box: the box
// around the object's visible mask) runs through the page with the segmenter: the first object
// through the URL contract (index.html?scene=&cameras=&view=&click=|box=&segmenter=&quality=
// [&maxSide=]),
// the others on the same page through window.vcarPage.segment (what a click on the viewer runs:
// the worker keeps the scene and OpenCV), so each object's seconds are a click's on a loaded page;
// the native twin runs the same prompt, segmenter and quality (first, before Chromium starts). Checks, per object: a selection
// that is neither empty nor the whole scene; Jaccard with the native selection >= --min-iou; the
// 3D F1 of the page's selection against the object's labelled Gaussians (`vcar eval`'s f1_3d:
// eval::selection_scores on gt/gaussian_ids.bin, the definition bench_field reports) >= its
// --min-f1 floor (objects not named there: only printed). With --spz: the page loads that SPZ
// file as it is (no prompt) and reports the Gaussian count its header declares, and its viewer
// shows it (Spark itself, or vcar's PLY of it where Spark cannot read the file: SPZ v4).
// Prints a line per object and one JSON line with every number (seconds split into renders,
// segmenter, vcar: web_session.hpp timing_split).
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { jaccard, launch, newPage, parseArgs, runNative, serve, unattended } from './harness.mjs';

const args = parseArgs(process.argv.slice(2));
const need = (k) => { if (!args[k]) { console.error(`missing --${k}`); process.exit(2); } return path.resolve(args[k]); };
const native = need('native'), cli = need('vcar');
const segmenter = args.segmenter ?? 'grabcut';
const promptKind = args.prompt ?? 'click';
if (!['click', 'box'].includes(promptKind)) { console.error('--prompt: click or box'); process.exit(2); }
const quality = args.quality ?? 'full';  // the page's quality= (grabcut.js vcarQualities), the native --quality
const maxSide = args['max-side'] === undefined ? undefined : Number(args['max-side']);  // overrides the quality's
const minIou = Number(args['min-iou'] ?? 0.98);
const minF1 = Object.fromEntries((args['min-f1'] ?? '').split(',').filter(Boolean).map((e) => e.split('=')).map(([k, v]) => [k, Number(v)]));
const timeoutMs = Number(args.timeout ?? 600) * 1000;
const run = (exe, argv) => execFileSync(exe, argv, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'inherit'], maxBuffer: 1 << 28 });
const since = (t) => Number(((Date.now() - t) / 1000).toFixed(1));
const r3 = (x) => Number(x.toFixed(3));

let failed = false;
function fail(msg) { console.error('FAIL: ' + msg); failed = true; }

// The dataset: given, or written by vcar synth.
let dataset = args.dataset ? path.resolve(args.dataset) : null, scratch = null;
const out = { segmenter, prompt: promptKind, quality, ...(maxSide ? { max_side: maxSide } : {}) };
if (!dataset) {
  scratch = fs.mkdtempSync(path.join(os.tmpdir(), 'vcar-stage-'));
  dataset = path.join(scratch, 'stage');
  const t = Date.now();
  run(cli, ['--quiet', 'synth', '--stage', need('stage'), '--seed', String(args.seed ?? 1), ...(args['synth-args'] ?? '').split(' ').filter(Boolean), '--out', dataset]);
  out.synth_seconds = since(t);
}
const prompt = JSON.parse(fs.readFileSync(path.join(dataset, 'prompt.json'), 'utf8'));
const objects = (prompt.objects ?? []).filter((o) => o.reference_view && o.points.length && o.labels.includes(1));
if (!objects.length) { console.error(`FAIL: ${dataset}/prompt.json has no object with a prompt (not a stage dataset?)`); process.exit(1); }
for (const name of Object.keys(minF1))
  if (!objects.some((o) => o.name === name)) fail(`--min-f1 names '${name}', which has no prompt in the dataset`);

const scene = path.join(dataset, 'scene.ply'), cameras = path.join(dataset, 'cameras.json');
// Each object's prompt, and the native twin's selection from it (before Chromium starts: its
// software-rendered viewer would take the cores from the native runs).
const prompts = objects.map((o) => ({ o, click: promptKind === 'click' ? o.points[o.labels.indexOf(1)] : null,
                                      box: promptKind === 'box' ? o.box : null }));
for (const p of prompts)
  p.nat = runNative(native, ['--scene', scene, '--cameras', cameras, '--view', p.o.reference_view,
                             ...(p.click ? ['--click', p.click.join(',')] : ['--box', p.box.join(',')]),
                             '--segmenter', segmenter, '--quality', quality, ...(maxSide ? ['--max-side', String(maxSide)] : [])]);
const inputs = { 'scene.ply': scene, 'cameras.json': cameras };
if (args.spz) inputs['input.spz'] = path.resolve(args.spz);
const server = await serve(inputs);
const browser = await launch(args.chromium);
const rows = [];
try {
  const page = await newPage(browser);
  const q = `scene=/input/scene.ply&cameras=/input/cameras.json&segmenter=${segmenter}&quality=${quality}${maxSide ? `&maxSide=${maxSide}` : ''}`;
  for (const [k, { o, click, box, nat }] of prompts.entries()) {
    let r;
    if (k === 0) {
      const p = click ? `click=${click.join(',')}` : `box=${box.join(',')}`;
      r = await unattended(page, `${server.base}/index.html?${q}&view=${encodeURIComponent(o.reference_view)}&${p}`, timeoutMs);
    } else {  // the same page: the reference camera by name, then the flow of a click (or box) on the viewer
      r = await page.evaluate(async (view, click, opts) => {
        const cam = (await window.vcarPage.call({ type: 'view', name: view })).camera;
        const s = await window.vcarPage.segment(cam, click ? click[0] : NaN, click ? click[1] : NaN, opts);
        return { selected: s.indices.length, indices: Array.from(s.indices), seconds: s.seconds,
                 split: { ...s.diagnostics.split, load_segmenter: s.loadSeconds } };
      }, o.reference_view, click, { segmenterName: segmenter, quality, ...(maxSide ? { maxSide } : {}), ...(box ? { box } : {}) });
    }
    rows.push({ o, click, box, r, nat, jaccard: jaccard(r.indices, nat.indices) });
  }

  // 3D F1 of the page's selections: one `vcar eval` run over a selection.json of several objects
  // (each scored against its object_id's labelled Gaussians).
  const sel = path.join(fs.mkdtempSync(path.join(os.tmpdir(), 'vcar-stage-sel-')), 'selection.json');
  fs.writeFileSync(sel, JSON.stringify({ objects: rows.map(({ o, r }) => ({ name: o.name, object_id: o.object_id, indices: r.indices })) }));
  const te = Date.now();
  const scores = JSON.parse(run(cli, ['--quiet', 'eval', '--dataset', dataset, '--selection', sel, '--json'])).objects;
  out.eval_seconds = since(te);
  fs.rmSync(path.dirname(sel), { recursive: true, force: true });
  const f1 = Object.fromEntries(scores.map((m) => [m.name, m]));

  out.objects = rows.map(({ o, click, box, r, nat, jaccard: iou }) => {
    const p = f1[o.name];
    const sp = r.split;
    const row = {
      name: o.name, object_id: o.object_id, view: o.reference_view, ...(click ? { click } : { box }),
      labelled: p.true, page_selected: r.selected, native_selected: nat.selected, jaccard: Number(iou.toFixed(5)),
      f1_3d: r3(p.f1_3d), precision_3d: r3(p.precision_3d), recall_3d: r3(p.recall_3d),
      page_seconds: r3(r.seconds),
      page_split: { renders: r3(sp.renders), segmenter: r3(sp.segmenter), vcar: r3(sp.vcar), load_segmenter: r3(sp.load_segmenter),
                    other: r3(r.seconds - sp.total - sp.load_segmenter) },
      native_seconds: r3(nat.seconds), native_split: { renders: r3(nat.split.renders), segmenter: r3(nat.split.segmenter), vcar: r3(nat.split.vcar) },
    };
    console.log(`stage: ${o.name}: page ${r.selected} / native ${nat.selected} Gaussians (${p.true} labelled), Jaccard ${row.jaccard}, ` +
                `3D F1 ${row.f1_3d} (precision ${row.precision_3d}, recall ${row.recall_3d}); page ${row.page_seconds} s = renders ${row.page_split.renders} + ` +
                `${segmenter} ${row.page_split.segmenter} + vcar ${row.page_split.vcar} + loading OpenCV ${row.page_split.load_segmenter} + ` +
                `other ${row.page_split.other}; native ${row.native_seconds} s`);
    if (!(r.selected > 0 && r.indices.length === r.selected)) fail(`${o.name}: the page selected ${r.selected}`);
    if (iou < minIou) fail(`${o.name}: Jaccard with the native selection ${iou.toFixed(4)} < ${minIou}`);
    if (o.name in minF1 && p.f1_3d < minF1[o.name]) fail(`${o.name}: 3D F1 ${p.f1_3d.toFixed(4)} < ${minF1[o.name]}`);
    return row;
  });
  const n = Number(execFileSync('head', ['-c', '4096', scene], { encoding: 'latin1' }).match(/element vertex (\d+)/)[1]);
  out.gaussians = n;
  for (const row of out.objects) if (row.page_selected >= n) fail(`${row.name}: the page selected the whole scene`);

  if (args.spz) {  // the SPZ file as it is: the count its header declares (u32 at byte 8), and the viewer shows it
    const head = fs.readFileSync(path.resolve(args.spz)).subarray(0, 12);
    const version = head.readUInt32LE(4), declared = head.readUInt32LE(8);
    const t = Date.now();
    await page.close();  // a fresh page: the stage's viewer is not unloaded first
    const r = await unattended(await newPage(browser), `${server.base}/index.html?scene=/input/input.spz`, timeoutMs);
    out.spz = { file: path.basename(args.spz), version, declared, page_gaussians: r.gaussians, format: r.format, viewer: r.viewer, seconds: since(t) };
    console.log(`stage: ${path.basename(args.spz)} (SPZ v${version}, ${declared} Gaussians declared) in the page: ${r.gaussians} Gaussians (${r.format}), viewer ${r.viewer}`);
    if (r.gaussians !== declared) fail(`${args.spz}: the page read ${r.gaussians} Gaussians, the header declares ${declared}`);
    if (!String(r.viewer).startsWith('ok')) fail(`${args.spz}: the viewer could not show it: ${r.viewer}`);
  }
} catch (e) {
  fail(e.message);
} finally {
  await browser.close();
  server.close();
  if (scratch) fs.rmSync(scratch, { recursive: true, force: true });
}
console.log(JSON.stringify(out));
process.exitCode = failed ? 1 : 0;
