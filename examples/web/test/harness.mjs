// What the headless-Chromium tests share (browser_test.mjs on one scene, stage_test.mjs on a
// stage of real objects): a static server for dist/ and the inputs, Debian's Chromium through
// puppeteer-core (no browser download), the page's unattended run, the native twin, Jaccard.
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import puppeteer from 'puppeteer-core';

export const dist = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..', 'dist');

// --key value pairs of argv as an object.
export function parseArgs(argv) {
  return Object.fromEntries(argv.reduce((a, v, i, all) => (v.startsWith('--') ? [...a, [v.slice(2), all[i + 1]]] : a), []));
}

// A static server on 127.0.0.1: dist/ at /, the files of `inputs` ({name: path}) at /input/<name>.
// Returns {base (the URL), close()}.
export async function serve(inputs) {
  const types = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css', '.json': 'application/json' };
  const server = http.createServer((req, res) => {
    const url = decodeURIComponent(req.url.split('?')[0]);
    const file = url.startsWith('/input/') ? inputs[url.slice(7)] : path.join(dist, path.normalize(url === '/' ? '/index.html' : url));
    if (!file || (!url.startsWith('/input/') && !file.startsWith(dist)) || !fs.existsSync(file)) { res.writeHead(404); res.end(); return; }
    res.writeHead(200, { 'Content-Type': types[path.extname(file)] ?? 'application/octet-stream' });
    fs.createReadStream(file).pipe(res);
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  return { base: `http://127.0.0.1:${server.address().port}`, close: () => server.close() };
}

// Headless Chromium with SwiftShader WebGL (the viewer runs on the CPU).
export function launch(chromium = '/usr/bin/chromium') {
  return puppeteer.launch({
    executablePath: chromium, headless: true,
    args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader', '--ignore-gpu-blocklist', '--window-size=1200,700'],
    defaultViewport: { width: 1200, height: 700 },
  });
}

// A page that keeps its console lines (page.logs) for error messages.
export async function newPage(browser) {
  const page = await browser.newPage();
  page.setDefaultNavigationTimeout(120000);  // a busy page (a large scene in SwiftShader) unloads slowly
  page.logs = [];
  page.on('console', (m) => page.logs.push(m.text()));
  page.on('pageerror', (e) => page.logs.push('pageerror: ' + e.message));
  return page;
}

// The page's unattended run at `url`: the JSON it writes into #vcar-result (throws on {"error"}).
export async function unattended(page, url, timeoutMs) {
  await page.goto(url);
  await page.waitForFunction(() => document.getElementById('vcar-result').textContent.length > 0, { timeout: timeoutMs, polling: 500 });
  const result = JSON.parse(await page.$eval('#vcar-result', (e) => e.textContent));
  if (result.error) throw new Error('page: ' + result.error + '\n' + page.logs.join('\n'));
  return result;
}

// The native twin (vcar_web_native) with these arguments: its JSON.
export function runNative(native, argv) {
  return JSON.parse(execFileSync(native, argv, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'inherit'], maxBuffer: 1 << 28 }));
}

// Jaccard overlap of two index lists; two empty ones agree (1).
export function jaccard(a, b) {
  const s = new Set(b);
  let both = 0;
  for (const i of a) both += s.has(i);
  const union = a.length + s.size - both;
  return union ? both / union : 1;
}
