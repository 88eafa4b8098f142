// Headless Chromium test of the page `imgtool compare` writes (run by
// run_browser_test.sh, which installs playwright-core into WORK_DIR):
// renders three small images, writes the page, opens it from file:// and checks
//  - no console error or page error while it loads and is used;
//  - keyboard flipping (1-9, left/right) changes the image shown; wheel zoom
//    and drag pan move the one view;
//  - every pixel read back from the WebGL canvas equals the EXR's value after
//    the same tone map, computed here from imgtool's PFM of the EXR (sRGB at
//    three exposures; false colour and relative error within 2/255);
//  - a pinned crop shows every image;
// and keeps screenshots in WORK_DIR. Exit 77 (ctest: skipped) only when
// Chromium cannot start, and then not under CI (CI=true): there it fails.
// usage: node compare_browser_test.mjs BIN_DIR WORK_DIR
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const [binDir, work] = process.argv.slice(2).map((a) => a && path.resolve(a));
if (!binDir || !work) {
  console.error('usage: node compare_browser_test.mjs BIN_DIR WORK_DIR');
  process.exit(2);
}
const here = path.dirname(fileURLToPath(import.meta.url));
const scene = path.join(here, '..', '..', 'scenes', 'cornell-box.pbrt');
const { chromium } = createRequire(path.join(work, 'package.json'))('playwright-core');

let passed = 0, failed = 0;
function check(name, ok, detail) {
  if (ok) ++passed;
  else ++failed;
  console.log((ok ? 'ok   ' : 'FAIL ') + name + (detail ? ': ' + detail : ''));
}

// ---------- the browser (first: a browser that cannot start ends the test at once) ----------
let browser;
try {
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'],
  });
} catch (e) {
  const why = 'chromium cannot start: ' + String(e.message).split('\n')[0];
  if (process.env.CI === 'true') {
    console.log('FAIL: ' + why + ' (CI=true requires the browser test to run)');
    process.exit(1);
  }
  console.log('SKIP: ' + why);
  process.exit(77);
}

// ---------- the images and the page ----------
const data = path.join(work, 'data'), page = path.join(work, 'page');
fs.rmSync(data, { recursive: true, force: true });
fs.rmSync(page, { recursive: true, force: true });
fs.mkdirSync(data, { recursive: true });
const W = 64, H = 48;
const renders = [['ref', 'path', 64, 7], ['path', 'path', 4, 1], ['bdpt', 'bdpt', 4, 2]];
for (const [name, integ, spp, seed] of renders) {
  execFileSync(path.join(binDir, 'gradus'), [scene, '--resolution', W + 'x' + H, '--integrator', integ, '--spp',
    String(spp), '--seed', String(seed), '--nthreads', '2', '--quiet', '--outfile', path.join(data, name + '.exr')]);
  execFileSync(path.join(binDir, 'imgtool'), ['convert', path.join(data, name + '.exr'), path.join(data, name + '.pfm')]);
}
execFileSync(path.join(binDir, 'imgtool'), ['compare', ...renders.map((r) => path.join(data, r[0] + '.exr')),
  '-o', page, '--exposure', '0.5']);
const pageBytes = fs.readdirSync(page).reduce((s, f) => s + fs.statSync(path.join(page, f)).size, 0);
const pageData = JSON.parse(fs.readFileSync(path.join(page, 'data.js'), 'utf8').replace(/^[^{]*/, '').replace(/;\s*$/, ''));

// PFM: float32 RGB rows bottom to top -> Float32Array, top row first.
function readPFM(file) {
  const buf = fs.readFileSync(file);
  let pos = 0;
  const token = () => {
    while (/\s/.test(String.fromCharCode(buf[pos]))) ++pos;
    const start = pos;
    while (!/\s/.test(String.fromCharCode(buf[pos]))) ++pos;
    return buf.toString('latin1', start, pos);
  };
  if (token() !== 'PF') throw new Error(file + ': not an RGB PFM');
  const w = Number(token()), h = Number(token()), scale = Number(token());
  ++pos;  // the single whitespace before the data
  const out = new Float32Array(w * h * 3);
  for (let y = 0; y < h; ++y)
    for (let i = 0; i < w * 3; ++i) {
      const at = pos + ((h - 1 - y) * w * 3 + i) * 4;
      out[y * w * 3 + i] = scale < 0 ? buf.readFloatLE(at) : buf.readFloatBE(at);
    }
  return out;
}
const linear = renders.map((r) => readPFM(path.join(data, r[0] + '.pfm')));
// The nearest half float (ties to even), as the page stores the data.
function toHalf(x) {
  if (!isFinite(x) || x === 0) return x;
  const a = Math.min(Math.abs(x), 65504), q = Math.pow(2, Math.max(Math.floor(Math.log2(a)), -14) - 10);
  const m = a / q;
  let r = Math.round(m);
  if (r - m === 0.5 && r % 2) r -= 1;
  return Math.sign(x) * r * q;
}
const halves = linear.map((img) => img.map(toHalf));

// The page's tone maps, written independently of viewer.js.
function srgbByte(v) {  // imgtool's PNG encoding
  if (!(v > 0)) return 0;
  if (v >= 1) return 255;
  const s = v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
  return Math.round(s * 255);
}
const RAMP = [[0, 0, 0], [0.35, 0.05, 0.55], [0.85, 0.1, 0.25], [1, 0.55, 0], [1, 0.95, 0.1], [1, 1, 1]];
function rampBytes(t) {
  const x = Math.min(Math.max(t, 0), 1) * 5, k = Math.min(Math.floor(x), 4), f = x - k;
  return RAMP[k].map((a, c) => Math.round(255 * (a + (RAMP[k + 1][c] - a) * f)));
}
function expected(k, mode, ev, source = linear) {
  const out = [], img = source[k], ref = source[0], scale = Math.pow(2, ev);
  for (let i = 0; i < W * H; ++i) {
    const v = [0, 1, 2].map((c) => img[i * 3 + c]);
    if (mode === 'sRGB') out.push(v.map((x) => srgbByte(Math.fround(x * scale))));
    else if (mode === 'false colour') {
      const y = (0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2]) * scale;
      out.push(y > 0 ? rampBytes((Math.log2(y) + 10) / 12) : [0, 0, 0]);
    } else {
      const r = [0, 1, 2].map((c) => ref[i * 3 + c]);
      const e = [0, 1, 2].reduce((s, c) => s + (v[c] - r[c]) ** 2 / (r[c] ** 2 + pageData.epsilon), 0) / 3;
      out.push(rampBytes(e / pageData.error_max));
    }
  }
  return out;
}
const allPixels = [];
for (let y = 0; y < H; ++y) for (let x = 0; x < W; ++x) allPixels.push([x, y]);

// ---------- the page in the browser ----------
const errors = [];
const tab = await browser.newPage({ viewport: { width: 1280, height: 860 }, deviceScaleFactor: 1 });
tab.on('console', (m) => { if (m.type() === 'error') errors.push('console: ' + m.text()); });
tab.on('pageerror', (e) => errors.push('page error: ' + e.message));
tab.on('requestfailed', (r) => errors.push('request failed: ' + r.url()));
const t0 = Date.now();
await tab.goto('file://' + path.join(page, 'index.html'));
await tab.waitForFunction(() => window.gradusReady === true, null, { timeout: 60000 });
check('page loads and draws', true, (Date.now() - t0) + ' ms, ' + (pageBytes / 1024).toFixed(1) + ' KiB in ' +
  fs.readdirSync(page).length + ' files');
const state = () => tab.evaluate(() => window.gradusState());
// 4 screen pixels per image pixel, the whole image in view.
await tab.evaluate(([w, h]) => window.gradusSetView(4, w / 2, h / 2), [W, H]);

// Figures in the table: imgtool diff's.
for (const k of [1, 2]) {
  const diff = JSON.parse(execFileSync(path.join(binDir, 'imgtool'), ['diff', path.join(data, renders[k][0] + '.exr'),
    path.join(data, 'ref.exr'), '--json']).toString());
  const cell = await tab.locator('#stats tr.img').nth(k).locator('td').nth(1).textContent();
  check('relMSE of ' + renders[k][0] + ' shown as imgtool diff computes it',
    Math.abs(Number(cell) - diff.relmse) <= 5e-4 * diff.relmse && pageData.images[k].metrics.relmse === diff.relmse,
    'page ' + cell + ', diff ' + diff.relmse);
}

let worst = 0, exact = 0, exactHalf = 0, compared = 0;
async function comparePixels(what, k, mode, ev, tolerance) {
  const got = await tab.evaluate((pts) => window.gradusReadPixels(pts), allPixels);
  const want = expected(k, mode, ev);
  let maxDiff = 0, same = 0, missing = 0;
  got.forEach((g, i) => {
    if (!g) { ++missing; return; }
    for (let c = 0; c < 3; ++c) {
      const d = Math.abs(g[c] - want[i][c]);
      maxDiff = Math.max(maxDiff, d);
      if (d === 0) ++same;
    }
  });
  // The same with the half-float rounding of the page's data modelled.
  const wantHalf = expected(k, mode, ev, halves);
  let sameHalf = 0;
  got.forEach((g, i) => { if (g) for (let c = 0; c < 3; ++c) sameHalf += g[c] === wantHalf[i][c]; });
  if (mode === 'sRGB') {
    worst = Math.max(worst, maxDiff);
    exact += same;
    exactHalf += sameHalf;
    compared += 3 * got.length;
  }
  const pct = (n) => (100 * n / (3 * got.length)).toFixed(2) + '%';
  check(what, missing === 0 && maxDiff <= tolerance, W * H + ' pixels, max |diff| ' + maxDiff + '/255, ' +
    pct(same) + ' of bytes exact (' + pct(sameHalf) + ' against the half-float values)' +
    (missing ? ', ' + missing + ' not visible' : ''));
  return got;
}

let s = await state();
check('opens on the first method at the page\'s exposure', s.current === 1 && s.exposure === 0.5 && s.mode === 'sRGB',
  JSON.stringify(s));
const shownPath = await comparePixels('sRGB pixels of path at +0.5 EV', 1, 'sRGB', 0.5, 1);
const shot1 = await tab.locator('#gl').screenshot();

// Wheel zoom keeps the image point under the cursor; dragging pans.
const glBox = await tab.locator('#gl').boundingBox(), pz = (await tab.evaluate(() => window.gradusPanels()))[0];
const mx = glBox.x + pz.x + pz.w / 2 + 40, my = glBox.y + pz.y + pz.h / 2 + 20;  // image point (W/2+10, H/2+5)
await tab.mouse.move(mx, my);
await tab.mouse.wheel(0, -240);
await tab.waitForFunction(() => window.gradusState().zoom === 8);
s = await state();
check('the wheel zooms about the cursor', s.zoom === 8 && s.cx + 40 / 8 === W / 2 + 10 && s.cy + 20 / 8 === H / 2 + 5,
  JSON.stringify(s));
await tab.mouse.down();
await tab.mouse.move(mx - 80, my - 40, { steps: 4 });
await tab.mouse.up();
const s2 = await state();
check('dragging pans', s2.cx === s.cx + 10 && s2.cy === s.cy + 5 && s2.crops === 0, JSON.stringify(s2));
await tab.evaluate(([w, h]) => window.gradusSetView(4, w / 2, h / 2), [W, H]);

// Flipping with the keyboard.
const flips = [['ArrowRight', 2], ['ArrowRight', 0], ['ArrowLeft', 2], ['1', 0], ['3', 2], ['2', 1], ['ArrowRight', 2]];
let flipsOk = true;
for (const [key, want] of flips) {
  await tab.keyboard.press(key);
  s = await state();
  if (s.current !== want) { flipsOk = false; check('key ' + key, false, 'shows ' + s.current + ', expected ' + want); }
}
check('keys 1-9 and left/right flip between the images', flipsOk, flips.map((f) => f[0]).join(' '));
const shownBdpt = await comparePixels('sRGB pixels of bdpt after flipping', 2, 'sRGB', 0.5, 1);
const changed = shownPath.filter((p, i) => p.some((v, c) => v !== shownBdpt[i][c])).length;
const shot2 = await tab.locator('#gl').screenshot();
check('flipping changes the image shown', changed > W * H / 4 && !shot1.equals(shot2),
  changed + ' of ' + W * H + ' pixels differ between path and bdpt');

// Exposure: ] and [ step by 0.5 EV.
await tab.keyboard.press(']');
s = await state();
check('] raises the exposure', s.exposure === 1, JSON.stringify(s.exposure));
await comparePixels('sRGB pixels of bdpt at +1 EV', 2, 'sRGB', 1, 1);
for (let i = 0; i < 4; ++i) await tab.keyboard.press('[');
await tab.keyboard.press('1');
await comparePixels('sRGB pixels of the reference at -1 EV', 0, 'sRGB', -1, 1);

// The other views.
await tab.keyboard.press('2');
await tab.keyboard.press('f');
await comparePixels('false-colour pixels of path', 1, 'false colour', -1, 2);
await tab.keyboard.press('e');
await comparePixels('relative-error pixels of path', 1, 'relative error', -1, 2);
await tab.keyboard.press('1');
const refErr = await tab.evaluate((pts) => window.gradusReadPixels(pts), allPixels);
check('relative error of the reference is black', refErr.every((p) => p && p[0] === 0 && p[1] === 0 && p[2] === 0));

// Side by side with a pinned crop (shift-drag), back in sRGB.
await tab.keyboard.press('s');
await tab.keyboard.press('2');
await tab.keyboard.press('g');
await tab.evaluate(([w, h]) => window.gradusSetView(4, w / 2, h / 2), [W, H]);
const box = await tab.locator('#gl').boundingBox();
// Image pixels [20, 36) x [16, 28) of the first panel, whose centre shows image point (W/2, H/2).
const p0 = await tab.evaluate(() => window.gradusPanels()[0]);
const toPage = (ix, iy) => [box.x + p0.x + p0.w / 2 + (ix - W / 2) * 4, box.y + p0.y + p0.h / 2 + (iy - H / 2) * 4];
await tab.keyboard.down('Shift');
await tab.mouse.move(...toPage(20.5, 16.5));
await tab.mouse.down();
await tab.mouse.move(...toPage(35.5, 27.5), { steps: 6 });
await tab.mouse.up();
await tab.keyboard.up('Shift');
await tab.waitForTimeout(200);
s = await state();
const cropCanvases = await tab.locator('#crop-list canvas').count();
check('shift-drag pins a crop of every image', s.crops === 1 && cropCanvases === renders.length,
  s.crops + ' crop(s), ' + cropCanvases + ' crop canvases');
// The crop of the current image (path) is its tone-mapped pixels at -1 EV.
const crop = await tab.evaluate(() => {
  const cv = document.querySelectorAll('#crop-list canvas')[1];
  return { w: cv.width, h: cv.height, px: Array.from(cv.getContext('2d').getImageData(0, 0, cv.width, cv.height).data) };
});
const want = expected(1, 'sRGB', -1);
let cropDiff = 0;
for (let y = 0; y < crop.h; ++y)
  for (let x = 0; x < crop.w; ++x)
    for (let c = 0; c < 3; ++c)
      cropDiff = Math.max(cropDiff, Math.abs(crop.px[(y * crop.w + x) * 4 + c] - want[(16 + y) * W + 20 + x][c]));
check('the crop holds the image\'s pixels', crop.w === 16 && crop.h === 12 && cropDiff <= 1,
  crop.w + 'x' + crop.h + ' at (20, 16), max |diff| ' + cropDiff);
check('side-by-side layout keeps one view', s.grid && s.zoom === 4, JSON.stringify(s));
await comparePixels('sRGB pixels of path side by side', 1, 'sRGB', -1, 1);

const shotFile = path.join(work, 'compare-screenshot.png');
await tab.screenshot({ path: shotFile, fullPage: true });
check('screenshot kept', fs.statSync(shotFile).size > 10000, shotFile);
check('no console error', errors.length === 0, errors.join('; '));
await browser.close();

console.log('sRGB read-back: ' + compared + ' bytes compared, ' + (100 * exact / compared).toFixed(2) +
  '% exact (' + (100 * exactHalf / compared).toFixed(2) + '% against the half-float values), max |diff| ' + worst +
  '/255; page ' + (pageBytes / 1024).toFixed(1) + ' KiB for ' + renders.length +
  ' images of ' + W + 'x' + H);
console.log(passed + ' passed, ' + failed + ' failed');
process.exit(failed ? 1 : 0);
