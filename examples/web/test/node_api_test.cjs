// The JavaScript API of vcar.js under Node (the page's worker uses the same calls), on a real
// trained scene (tests/data/train-1000.ply): loading, errors as messages, the JavaScript
// segmenter hook (called per frame, reference first, masks checked for size), indices, scores,
// log-scales, the PLY bytes and several objects at once (segmentObjects). Exits non-zero on the first failed check.
//   node test/node_api_test.cjs dist/vcar.js ../../tests/data/train-1000.ply [SCENE.splat SCENE.spz
//        [V4.spz V4-AS-V3.spz]]
// The optional files (the same scene converted by `vcar_web_native --convert`) check the other
// formats: .splat as is, SPZ inflated first (zlib here, DecompressionStream in the page). With
// an SPZ v4 file (zstd streams) and its natively converted gzip copy: v4 is read through fzstd
// (dist/vendor/fzstd, as the worker loads it) and agrees with the copy; without fzstd it fails
// with a message that names the missing decoder.
//   V4.spz: e.g. ../shared/data/biker.spz (a current SPZ writer's output).
const fs = require('fs');
const path = require('path');
const [vcarJs, scenePath, splatPath, spzPath, spz4Path, spz4As3Path] = process.argv.slice(2);
const createVcar = require(path.resolve(vcarJs));
let failed = 0;
const check = (ok, what) => { if (!ok) { failed++; console.error('FAIL: ' + what); } };
const vertexCount = (b) => Number(/element vertex (\d+)/.exec(Buffer.from(b.subarray(0, 2000)).toString('latin1'))[1]);

(async () => {
  const vcar = await createVcar();
  const msg = (f) => { try { f(); return null; } catch (e) { return typeof e === 'number' ? vcar.exceptionMessage(e) : String(e); } };
  const s = new vcar.Session();
  check(/no scene loaded/.test(msg(() => s.defaultView(64, 48))), 'defaultView before a scene names the problem');
  check(/unrecognised scene file/.test(msg(() => s.loadScene(new Uint8Array([1, 2, 3, 4, 5]), 'x.bin'))), 'garbage is rejected by content');
  const n = s.loadScene(fs.readFileSync(scenePath), 'train-1000.ply');
  check(n === 1000 && s.size() === 1000 && s.format() === 'PLY', `loaded ${n} Gaussians as ${s.format()}`);
  if (splatPath) {
    const o = new vcar.Session();
    check(o.loadScene(fs.readFileSync(splatPath), 'scene.splat') === 1000 && o.format() === '.splat', `.splat: ${o.format()}`);
    const gz = fs.readFileSync(spzPath);
    check(gz[0] === 0x1f && gz[1] === 0x8b, 'the SPZ file is gzip (v3)');
    check(o.loadScene(require('zlib').gunzipSync(gz), 'scene.spz') === 1000 && o.format() === 'SPZ', `SPZ: ${o.format()}`);
    const sameCam = o.defaultView(160, 120), plyCam = s.defaultView(160, 120);
    check(Math.abs(sameCam.t[2] - plyCam.t[2]) < 1e-2 * Math.abs(plyCam.t[2]) + 1e-3, 'SPZ positions agree with the PLY (default view)');
    o.delete();
  }
  if (spz4Path) {
    const v4 = fs.readFileSync(spz4Path);
    check(v4.readUInt32LE(0) === 0x5053474e && v4.readUInt32LE(4) === 4, 'the v4 file is SPZ version 4');
    const o = new vcar.Session();
    check(/no zstd decoder/.test(msg(() => o.loadScene(v4, 'scene.spz'))), 'SPZ v4 without fzstd names the missing decoder');
    globalThis.fzstd = require(path.join(path.dirname(path.resolve(vcarJs)), 'vendor', 'fzstd', 'fzstd.js'));
    const n4 = o.loadScene(v4, 'scene.spz');
    const c = new vcar.Session();
    const n3 = c.loadScene(require('zlib').gunzipSync(fs.readFileSync(spz4As3Path)), 'scene.spz');
    check(n4 > 0 && n4 === n3 && o.format() === 'SPZ', `SPZ v4: ${n4} Gaussians, ${n3} in the native conversion`);
    const a = o.defaultView(160, 120), b = c.defaultView(160, 120);
    check(a.t.every((v, k) => Math.abs(v - b.t[k]) < 1e-4 * (1 + Math.abs(b.t[k]))), 'SPZ v4 positions agree with the native reading (default view)');
    const corrupt = Buffer.from(v4);
    corrupt.fill(0xab, corrupt.length - 4096);  // the last stream's tail
    check(/SPZ v4 stream/.test(msg(() => o.loadScene(corrupt, 'bad.spz')) || ''), 'a corrupt v4 stream is an error naming the stream');
    o.delete();
    c.delete();
  }
  const cam = s.defaultView(160, 120);
  check(cam.width === 160 && cam.R.length === 9 && cam.t.length === 3, 'defaultView is a camera object');

  // A JavaScript segmenter: the covered (non-black) pixels of each frame. Called once per frame
  // of each round, reference (index 0) first, with w*h*3 RGB bytes.
  const calls = [];
  const covered = (f) => {
    calls.push({ index: f.index, fine: f.fine, w: f.width, h: f.height, bytes: f.rgb.length });
    const m = new Uint8Array(f.width * f.height);
    let on = 0;
    for (let i = 0; i < m.length; ++i) on += m[i] = (f.rgb[3 * i] | f.rgb[3 * i + 1] | f.rgb[3 * i + 2]) > 8 ? 1 : 0;
    return on ? m : null;
  };
  // the click: the most opaque pixel of vcar's own render of the view
  const img = s.render(cam);
  check(img.rgb.length === 160 * 120 * 3 && img.alpha.length === 160 * 120, 'render gives w*h*3 RGB and w*h alpha');
  let best = 0;
  for (let i = 1; i < img.alpha.length; ++i) if (img.alpha[i] > img.alpha[best]) best = i;
  const [u, v] = [best % 160 + 0.5, Math.floor(best / 160) + 0.5];
  check(img.alpha[best] > 0.5, 'some pixel is covered');
  const d = s.segment(cam, u, v, { segmenter: covered, orbitViews: 4 }, null);
  check(calls.length >= 5 && calls[0].index === 0 && !calls[0].fine, `hook called per frame, reference first (${calls.length} calls)`);
  check(calls.every((c) => c.bytes === c.w * c.h * 3), 'frames carry w*h*3 RGB bytes');
  const idx = s.indices(), scores = s.scores(), ls = s.logScales();
  check(idx.length === d.selected && idx.length > 0 && idx.length <= 1000, `selected ${idx.length}`);
  check(scores.length === idx.length && ls.length === 3 * idx.length, 'scores and log-scales align with indices');
  check(idx.every((v, i) => i === 0 || v > idx[i - 1]), 'indices ascending');
  check(vertexCount(s.objectPly()) === idx.length, 'object PLY holds the selection');
  check(vertexCount(s.removedPly()) === 1000 - idx.length, 'removed PLY holds the rest');
  const st = s.statePly();
  check(vertexCount(st) === 1000 && /property uchar state/.test(Buffer.from(st.subarray(0, 4000)).toString('latin1')), 'state PLY: every Gaussian + a state byte');

  // Several objects (vcar::segment_objects): one prompt gives segment's selection; two prompts
  // ask the hook per object (frame.object) and come back disjoint (conflicts resolved by score).
  const one = s.segmentObjects(cam, [{ click: [u, v] }], { segmenter: covered, orbitViews: 4 }, null);
  const o0 = s.objectIndices(0);
  check(one.length === 1 && o0.length === idx.length && o0.every((x, i) => x === idx[i]), 'one prompt: segmentObjects selects what segment does');
  const asked = new Set();
  const two = s.segmentObjects(cam, [{ click: [u, v], name: 'clicked' }, { box: [0, 0, 80, 120], click: null }],
                               { segmenter: (f) => { asked.add(f.object); return covered(f); }, orbitViews: 4 }, null);
  const a = s.objectIndices(0), inA = new Set(a);
  check(two.length === 2 && asked.has(0) && asked.has(1), 'two prompts: the hook is asked for each object');
  check(s.objectIndices(1).every((x) => !inA.has(x)), 'two prompts: no Gaussian in both objects');
  check(/no object 2/.test(msg(() => s.objectIndices(2)) || ''), 'objectIndices past the objects names the problem');

  // A wrong-size mask is an error naming the hook.
  const bad = msg(() => s.segment(cam, u, v, { segmenter: () => new Uint8Array(7), orbitViews: 2 }, null));
  check(/options\.segmenter/.test(bad || ''), 'a wrong-size mask names options.segmenter: ' + bad);
  // Progress: stages in order, and returning false cancels.
  const stages = [];
  s.segment(cam, u, v, { segmenter: covered, orbitViews: 2 }, (p) => { stages.push(p.stage); return true; });
  check(stages[0] === 'coarse' && stages[stages.length - 1] === 'done', 'progress from coarse to done: ' + [...new Set(stages)].join(','));
  const cancelled = msg(() => s.segment(cam, u, v, { segmenter: covered, orbitViews: 2 }, () => false));
  check(/cancelled/.test(cancelled || ''), 'progress returning false cancels: ' + cancelled);
  console.log(failed ? `node API test: ${failed} failed` : `node API test: PASS (${calls.length} frames through the JS hook, ${idx.length} selected)`);
  process.exit(failed ? 1 : 0);
})();
