// Drives Debian's headless Chromium (puppeteer-core, no browser download) against
// examples/web/dist on real trained Gaussians, and checks the page's selection against the
// native twin (vcar_web_native: the same Session, segmenter and parameters, built for x86-64).
//
//   node test/browser_test.mjs --native BUILD/vcar_web_native --scene tests/data/donut.ply \
//        --click 200,240 [--cameras cams.json --view NAME] [--segmenter grabcut|region]
//        [--screenshots docs/figures] [--min-iou 0.98] [--objects U,V;U,V]
// --segmenter (default region): the page's segmenter (URL segmenter=, and the select for the
// canvas click) and the native twin's (grabcut: OpenCV's WebAssembly build in the page,
// Debian's OpenCV natively).
//
// Checks: the page writes {"selected", "seconds", "indices"} into #vcar-result; the selection is
// not empty and not the whole scene; its Jaccard overlap with the native selection is at least
// --min-iou; a mouse click on the canvas at the same spot (the viewer's camera converted to a
// vcar camera) selects an overlapping set (Jaccard >= --min-click-iou, 0.7: the reference view
// then differs, see there); the PLY bytes the page offers have the right vertex counts (object =
// selected, removed = n - selected, state PLY = n with exactly `selected` bytes with bit 0 set).
// With --objects (a click per object on the same view): the page's objects= flow
// (vcar::segment_objects) against the native twin's --objects: as many objects, the first one
// not empty, no Gaussian in two objects, each object's Jaccard with the native one >= --min-iou
// (two empty selections agree: an object can lose all its Gaussians to an earlier one).
// Prints one JSON line with the numbers (browser and native seconds of the same run).
import path from 'node:path';
import { jaccard, launch, newPage, parseArgs, runNative as runTwin, serve, unattended } from './harness.mjs';

const args = parseArgs(process.argv.slice(2));
const need = (k) => { if (!args[k]) { console.error(`missing --${k}`); process.exit(2); } return args[k]; };
const scene = path.resolve(need('scene'));
const click = need('click');
const native = path.resolve(need('native'));
const minIou = Number(args['min-iou'] ?? 0.98);
const minClickIou = Number(args['min-click-iou'] ?? 0.7);
const timeoutMs = Number(args.timeout ?? 300) * 1000;
const chromium = args.chromium ?? '/usr/bin/chromium';
const segmenter = args.segmenter ?? 'region';
const maxSide = args['max-side'];  // the page's maxSide (URL) and the native --max-side: views rendered this small

// A static server: dist/ at /, the inputs at /input/<name>.
const inputs = { [path.basename(scene)]: scene };
if (args.cameras) inputs[path.basename(args.cameras)] = path.resolve(args.cameras);
const server = await serve(inputs);
const base = server.base;

function fail(msg) { console.error('FAIL: ' + msg); process.exitCode = 1; }

// The native twin on the same scene, cameras, view, segmenter and view size, with `prompt`
// (['--click', 'u,v'] or ['--objects', 'u,v;u,v']): its JSON.
function runNative(prompt) {
  return runTwin(native, ['--scene', scene, ...prompt, '--segmenter', segmenter,
    ...(maxSide ? ['--max-side', String(maxSide)] : []),
    ...(args.cameras ? ['--cameras', path.resolve(args.cameras)] : []), ...(args.view ? ['--view', args.view] : [])]);
}

const browser = await launch(chromium);
const out = {};
try {
  const page = await newPage(browser);
  let q = `scene=/input/${encodeURIComponent(path.basename(scene))}`;
  if (args.cameras) q += `&cameras=/input/${encodeURIComponent(path.basename(args.cameras))}`;
  if (args.view) q += `&view=${encodeURIComponent(args.view)}`;
  q += `&segmenter=${segmenter}`;
  const qSide = maxSide ? `&maxSide=${maxSide}` : '';
  const shots = args.screenshots ? path.resolve(args.screenshots) : null;

  if (shots) {  // before: the scene in the viewer, nothing selected
    await page.goto(`${base}/index.html?${q}`);
    await page.waitForFunction(() => /Gaussians/.test(document.getElementById('status').textContent), { timeout: timeoutMs });
    await new Promise((r) => setTimeout(r, 4000));
    await page.screenshot({ path: path.join(shots, 'web_before.png') });
  }
  const result = await unattended(page, `${base}/index.html?${q}${qSide}&click=${click}`, timeoutMs);
  if (shots) {
    await new Promise((r) => setTimeout(r, 3000));
    await page.screenshot({ path: path.join(shots, 'web_after.png') });
    await page.evaluate(() => window.vcarPage.display('isolate'));
    await new Promise((r) => setTimeout(r, 3000));
    await page.screenshot({ path: path.join(shots, 'web_isolate.png') });
  }
  // (--canvas-click off skips what follows down to the PLY checks: a second run of one flow.)
  // A click on the canvas at the same spot: the viewer's camera (three.js) becomes a vcar camera
  // (an extra, 17th view of the canvas' size), so the selection is not identical to the
  // unattended one, but a wrong axis or intrinsics conversion would land the click elsewhere.
  const canvasClick = args['canvas-click'] !== 'off';
  const box = await page.$eval('#canvas', (c) => { const r = c.getBoundingClientRect(); return { x: r.left, y: r.top, w: r.width, h: r.height }; });
  const ref = await page.evaluate(() => Array.from(window.vcarPage.selection()));
  const [cu, cv] = click.split(',').map(Number);
  const refCam = await page.evaluate((v) => window.vcarPage.call({ type: 'view', name: v }), args.view ?? '');
  let clicked = ref;
  if (canvasClick) {
    await page.evaluate((name) => {
      document.getElementById('status').textContent = '';
      document.getElementById('segmenter-select').value = name;
    }, segmenter);
    await page.mouse.click(box.x + cu * box.w / refCam.camera.width, box.y + cv * box.h / refCam.camera.height);
    await page.waitForFunction(() => /^selected|^error/.test(document.getElementById('status').textContent), { timeout: timeoutMs, polling: 500 });
    clicked = await page.evaluate(() => Array.from(window.vcarPage.selection() || []));
  }
  const clickIou = jaccard(clicked, ref);

  // The PLY files the page offers for download (of the canvas click's selection).
  const header = async (kind) => page.evaluate(async (k) => {
    const r = await window.vcarPage.call({ type: 'ply', kind: k });
    const b = new Uint8Array(r.bytes);
    const text = new TextDecoder('latin1').decode(b.subarray(0, 4096));
    const end = text.indexOf('end_header\n') + 'end_header\n'.length;
    const n = Number(/element vertex (\d+)/.exec(text)[1]);
    const props = [...text.slice(0, end).matchAll(/property (\w+) (\w+)/g)].map((m) => [m[1], m[2]]);
    let state = null;
    if (props.length && props[props.length - 1][1] === 'state') {  // uchar last: stride = 4 * (props - 1) + 1
      const stride = 4 * (props.length - 1) + 1;
      state = 0;
      for (let i = 0; i < n; ++i) state += b[end + i * stride + stride - 1] & 1;
    }
    return { n, state };
  }, kind);
  const obj = await header('object'), rem = await header('removed'), st = await header('state');

  const nat = runNative(['--click', click]);
  const iou = jaccard(result.indices, nat.indices);
  const total = obj.n + rem.n;
  Object.assign(out, {
    scene: path.basename(scene), click, view: args.view ?? null, segmenter, gaussians: total,
    browser_selected: result.selected, native_selected: nat.selected, identical: iou === 1,
    jaccard: Number(iou.toFixed(5)), browser_seconds: Number(result.seconds.toFixed(3)), browser_split: result.split,
    native_seconds: Number(nat.seconds.toFixed(3)), ratio: Number((result.seconds / nat.seconds).toFixed(2)),
    simd: result.simd, ply: { object: obj.n, removed: rem.n, state_n: st.n, state_selected: st.state },
    canvas_click: canvasClick ? { selected: clicked.length, jaccard_vs_unattended: Number(clickIou.toFixed(4)) } : null,
  });
  if (!(result.selected > 0 && result.selected < total)) fail(`selection of ${result.selected} of ${total} Gaussians`);
  if (result.indices.length !== result.selected) fail('indices and selected disagree');
  if (iou < minIou) fail(`Jaccard overlap with the native selection ${iou.toFixed(4)} < ${minIou}`);
  if (clickIou < minClickIou) fail(`canvas click: Jaccard ${clickIou.toFixed(4)} with the unattended selection < ${minClickIou}`);
  if (obj.n !== clicked.length) fail(`object.ply has ${obj.n} vertices, ${clicked.length} selected`);
  if (rem.n !== total - clicked.length || st.n !== total) fail(`removed.ply ${rem.n} / state PLY ${st.n} vertices for ${total}`);
  if (st.state !== clicked.length) fail(`state PLY marks ${st.state} selected, ${clicked.length} expected`);
  if (args.objects) {  // several objects: the page's objects= against the native twin's --objects
    const multi = await unattended(page, `${base}/index.html?${q}${qSide}&objects=${encodeURIComponent(args.objects)}`, timeoutMs);
    const natMulti = runNative(['--objects', args.objects]);
    const wanted = args.objects.split(';').length;
    const seen = new Set();
    let shared = 0;
    const jaccards = multi.objects.map((o, k) => {
      for (const i of o.indices) { shared += seen.has(i); seen.add(i); }
      return jaccard(o.indices, natMulti.objects[k] ? natMulti.objects[k].indices : []);  // both empty: 1 (an object may lose all to another)
    });
    out.objects = { selected: multi.objects.map((o) => o.selected), jaccard: jaccards.map((x) => Number(x.toFixed(5))),
                    browser_seconds: Number(multi.seconds.toFixed(3)), native_seconds: Number(natMulti.seconds.toFixed(3)) };
    if (multi.objects.length !== wanted || natMulti.objects.length !== wanted) fail(`objects: ${multi.objects.length} in the page, ${natMulti.objects.length} native, ${wanted} asked`);
    if (!(multi.objects[0].selected > 0)) fail('objects: the first object selected nothing');
    if (shared) fail(`objects: ${shared} Gaussians in two objects`);
    if (!jaccards.every((x) => x >= minIou)) fail(`objects: Jaccard with the native selections ${jaccards.join(', ')} < ${minIou}`);
  }
} catch (e) {
  fail(e.message);
} finally {
  await browser.close();
  server.close();
}
console.log(JSON.stringify(out));
