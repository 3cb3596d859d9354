// vcar in a Web Worker: the page posts scene and camera bytes and a click; vcar (WebAssembly,
// vcar.js) segments and posts progress, then the selection. One request at a time.
//
// Messages in:  {type: 'scene', bytes, name} | {type: 'cameras', bytes, name} | {type: 'view', name}
//               {type: 'default-view', width, height}
//               {type: 'segment', camera, u, v, options} | {type: 'ply', kind: 'object'|'removed'|'state'|'scene'}
//               {type: 'segment-objects', camera, prompts: [{click: [u, v] | null, box: [...] | null}], options}
//               (options: {segmenterName: 'grabcut' | 'region', quality: 'full' | 'fast',
//               box: [x0, y0, x1, y1], maxSide, ...};
//               u, v NaN: no click, the box alone)
// Messages out: {type: 'ready', simd} | {type: 'progress', stage, view, views, elapsed}
//               {type: 'scene', n, format} | {type: 'cameras', names} | {type: 'view', camera}
//               {type: 'result', indices, scores, logScales, diagnostics, seconds, loadSeconds}
//               {type: 'objects', objects: [{indices, diagnostics}], seconds, loadSeconds}  (one per prompt)
//               (seconds: the request, click to selection; loadSeconds: loading OpenCV, its first
//               GrabCut request only; diagnostics.split: vcar::segment's seconds as renders,
//               segmenter and vcar, web_session.hpp timing_split)
//               {type: 'ply', kind, bytes} | {type: 'error', message, request}
importScripts('vcar.js', 'vendor/fzstd/fzstd.js', 'grabcut.js');  // fzstd: SPZ v4's zstd streams (self.fzstd); grabcut.js: GrabCut on OpenCV's cv, once loaded

let vcar = null, session = null;
const ready = createVcar().then((m) => {
  vcar = m;
  session = new vcar.Session();
  postMessage({ type: 'ready', simd: vcar.simdPath() });
});

// C++ exceptions arrive as a pointer (a number); vcar.exceptionMessage reads their what().
function messageOf(e) {
  if (typeof e === 'number' && vcar) return vcar.exceptionMessage(e);
  return e && e.message ? e.message : String(e);
}

// SPZ v2/v3 is one gzip stream: the browser inflates it (vcar's wasm build has no zlib).
async function maybeGunzip(bytes) {
  if (bytes.length >= 2 && bytes[0] === 0x1f && bytes[1] === 0x8b) {
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('gzip'));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }
  return bytes;
}

// The page's segmenters (options.segmenterName): 'grabcut' (the default: OpenCV's GrabCut in
// WebAssembly on each frame's box, grabcut.js; OpenCV is loaded on first use, ~11 MB) or 'region'
// (vcar's colour + depth region growing from the click, in vcar.js). cv is handed over wrapped:
// emscripten's module object is a thenable, which a promise would try to adopt.
let openCV = null;
function loadOpenCV() {
  if (!openCV) {
    openCV = new Promise((resolve, reject) => {
      try {
        importScripts('vendor/opencv/opencv.js');
      } catch (e) {
        reject(new Error('OpenCV could not be loaded (vendor/opencv/opencv.js): ' + e.message));
        return;
      }
      const cv = self.cv;
      if (cv.Mat) resolve({ cv });
      else cv.onRuntimeInitialized = () => resolve({ cv });
    });
  }
  return openCV;
}

// Hook for a segmenter written in JavaScript (docs/web.md, "Bring your own SAM"): a script
// imported here (options.segmenterScript, same origin) that defines
//   self.vcarSegmenter = (frame) => Uint8Array (w*h, nonzero = object) | null
// frame = {index, camera, width, height, rgb: Uint8Array (w*h*3), click: [u, v], fine}; frame 0
// is the reference view the click is on; fine: the fine round (renders of the coarse selection).
// It runs synchronously inside vcar::segment.
function hostSegmenter(options) {
  if (!options || !options.segmenterScript) return undefined;
  importScripts(options.segmenterScript);
  if (typeof self.vcarSegmenter !== 'function') throw new Error(options.segmenterScript + ' defines no self.vcarSegmenter');
  return self.vcarSegmenter;
}

onmessage = async (ev) => {
  const q = ev.data;
  await ready;
  try {
    if (q.type === 'scene') {
      const bytes = await maybeGunzip(new Uint8Array(q.bytes));
      const n = session.loadScene(bytes, q.name);
      postMessage({ type: 'scene', n, format: session.format() });
    } else if (q.type === 'cameras') {
      if (q.bytes) session.loadCameras(new Uint8Array(q.bytes), q.name);
      else session.clearCameras();
      postMessage({ type: 'cameras', names: session.cameraNames() });
    } else if (q.type === 'view') {
      postMessage({ type: 'view', camera: session.referenceView(q.name || '') });
    } else if (q.type === 'default-view') {
      postMessage({ type: 'view', camera: session.defaultView(q.width, q.height) });
    } else if (q.type === 'segment' || q.type === 'segment-objects') {
      const t0 = performance.now();
      const options = { ...(q.options || {}) };
      const name = options.segmenterName || 'grabcut';
      delete options.segmenterName;
      // options.quality (grabcut.js vcarQualities): the views' size unless maxSide is given, and
      // GrabCut's crop and iterations.
      const quality = options.quality || 'full';
      delete options.quality;
      const preset = self.vcarQualities[quality];
      if (!preset) throw new Error(`unknown quality '${quality}' (${Object.keys(self.vcarQualities).join(' or ')})`);
      if (options.maxSide === undefined) options.maxSide = preset.maxSide;
      const grabcutParams = { ...self.vcarGrabCutParams, context: preset.context, iterations: preset.iterations };
      let seg = hostSegmenter(options);
      delete options.segmenterScript;
      let loadSeconds = 0;  // loading OpenCV (the first GrabCut request only): part of `seconds`
      if (!seg && name === 'grabcut') {
        const { cv } = await loadOpenCV();
        loadSeconds = (performance.now() - t0) / 1000;
        seg = (frame) => self.vcarGrabCut(cv, frame, grabcutParams);
      } else if (!seg && name !== 'region') {
        throw new Error(`unknown segmenter '${name}' (grabcut or region)`);
      }
      if (seg) options.segmenter = seg;
      const progress = (p) => {
        postMessage({ type: 'progress', ...p });
        return true;
      };
      if (q.type === 'segment-objects') {  // vcar::segment_objects: one coarse round for all
        const diagnostics = session.segmentObjects(q.camera, q.prompts, options, progress);
        const objects = diagnostics.map((d, k) => ({ indices: session.objectIndices(k), diagnostics: d }));
        const seconds = (performance.now() - t0) / 1000;
        postMessage({ type: 'objects', objects, seconds, loadSeconds }, objects.map((o) => o.indices.buffer));
        return;
      }
      const diagnostics = session.segment(q.camera, q.u, q.v, options, progress);
      const seconds = (performance.now() - t0) / 1000;
      const indices = session.indices(), scores = session.scores(), logScales = session.logScales();
      postMessage({ type: 'result', indices, scores, logScales, diagnostics, seconds, loadSeconds },
                  [indices.buffer, scores.buffer, logScales.buffer]);
    } else if (q.type === 'ply') {
      const bytes = q.kind === 'object' ? session.objectPly() : q.kind === 'removed' ? session.removedPly()
        : q.kind === 'scene' ? session.scenePly() : session.statePly();
      postMessage({ type: 'ply', kind: q.kind, bytes }, [bytes.buffer]);
    }
  } catch (e) {
    postMessage({ type: 'error', message: messageOf(e), request: q.type });
  }
};
