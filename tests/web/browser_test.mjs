// The browser viewer's test (samples/web): serves the built page on localhost, opens it in headless Chromium
// (Debian's, driven through playwright-core), presses on the left hand and drags it to a far point, and checks the
// screenshots:
//   1. rest: the character is drawn, whole (a silhouette of plausible size on the plain background);
//   2. reaching (the button held 1.5 s): the arm is stretched — the page reports the stretch, the hand is drawn where
//      the page says it is, where nothing was drawn at rest, and the silhouette reaches further toward the point;
//   3. released (3 s later): the arm has sprung back to its rest length.
// These run on ?bare (the character alone). Then the whole page (panel, floor, lattices) is shot reaching, and the
// walk chosen in its panel plays (the clip's time advances). Any error in the page's console fails the test.
//   node tests/web/browser_test.mjs BUILD_DIR OUT_DIR     (BUILD_DIR: index.html, deform_web.js, deform_web.wasm)
// Writes OUT_DIR/{rest,reach,released,page}.png; exits 1 with the reasons when a check fails.
import { createServer } from 'node:http';
import { mkdirSync, readFileSync, writeFileSync, renameSync } from 'node:fs';
import { extname, join, resolve } from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const { chromium } = require('../node/node_modules/playwright-core');

const [buildDir, outDir] = process.argv.slice(2).map((p) => p && resolve(p));
if (!buildDir || !outDir) {
  console.error('usage: node tests/web/browser_test.mjs BUILD_DIR OUT_DIR');
  process.exit(2);
}
mkdirSync(outDir, { recursive: true });

const types = { '.html': 'text/html', '.js': 'text/javascript', '.wasm': 'application/wasm' };
const server = createServer((request, response) => {
  const name = new URL(request.url, 'http://localhost').pathname.replace(/^\/+/, '') || 'index.html';
  if (!(name in { 'index.html': 1, 'deform_web.js': 1, 'deform_web.wasm': 1 })) {
    response.writeHead(404).end();
    return;
  }
  response.writeHead(200, { 'Content-Type': types[extname(name)] });
  response.end(readFileSync(join(buildDir, name)));
});
await new Promise((ready) => server.listen(0, '127.0.0.1', ready));
const origin = `http://127.0.0.1:${server.address().port}`;

const failures = [];
const check = (ok, what) => {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures.push(what);
};
// Written whole or not at all: the PNG goes to a temporary name first.
const save = (name, png) => {
  writeFileSync(join(outDir, name + '.tmp'), png);
  renameSync(join(outDir, name + '.tmp'), join(outDir, name));
};

// WebGL2 without a GPU: SwiftShader through ANGLE.
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
const consoleErrors = [];
async function open(query) {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  page.on('console', (m) => m.type() === 'error' && consoleErrors.push(m.text()));
  page.on('pageerror', (e) => consoleErrors.push(String(e)));
  await page.goto(`${origin}/index.html${query}`);
  await page.waitForSelector('body[data-ready="1"]', { timeout: 60000 });
  await frames(page, 5, 500);
  return page;
}
const state = (page) => page.evaluate(() => window.deformState());
// Waits until the page has drawn `count` more frames (and at least `ms` milliseconds have passed).
async function frames(page, count, ms = 0) {
  const start = (await state(page)).frames;
  await page.waitForTimeout(ms);
  await page.waitForFunction((n) => window.deformState().frames >= n, start + count, { timeout: 60000 });
}

// Presses on the left wrist, drags to the far point and holds it there 1.5 s (30 frames at least).
async function reachFar(page, bounds) {
  const wrist = (await state(page)).hand_l_pixel;
  await page.mouse.move(bounds.x + wrist[0], bounds.y + wrist[1]);
  await page.mouse.down();
  await frames(page, 2);
  await page.mouse.move(bounds.x + 0.87 * bounds.width, bounds.y + 0.62 * bounds.height, { steps: 12 });
  await frames(page, 10, 1500);
}

// The silhouette of a canvas screenshot: the pixels that differ from the background (the top-left pixel's colour)
// by more than 40 (sum over RGB), decoded by the browser itself. Box, count, and whether a pixel is in it.
async function silhouette(page, png, probe) {
  return page.evaluate(async ({ data, probe }) => {
    const image = new Image();
    image.src = 'data:image/png;base64,' + data;
    await image.decode();
    const canvas = new OffscreenCanvas(image.width, image.height);
    const context = canvas.getContext('2d');
    context.drawImage(image, 0, 0);
    const p = context.getImageData(0, 0, image.width, image.height).data;
    const differs = (i) => Math.abs(p[i] - p[0]) + Math.abs(p[i + 1] - p[1]) + Math.abs(p[i + 2] - p[2]) > 40;
    const box = { left: Infinity, right: -Infinity, top: Infinity, bottom: -Infinity, count: 0 };
    for (let y = 0; y < image.height; ++y)
      for (let x = 0; x < image.width; ++x)
        if (differs(4 * (y * image.width + x))) {
          box.count++;
          box.left = Math.min(box.left, x), box.right = Math.max(box.right, x);
          box.top = Math.min(box.top, y), box.bottom = Math.max(box.bottom, y);
        }
    // The probe: any silhouette pixel within 6 pixels of the given point.
    box.probe = false;
    if (probe)
      for (let y = Math.round(probe[1]) - 6; y <= Math.round(probe[1]) + 6; ++y)
        for (let x = Math.round(probe[0]) - 6; x <= Math.round(probe[0]) + 6; ++x)
          if (x >= 0 && y >= 0 && x < image.width && y < image.height && differs(4 * (y * image.width + x)))
            box.probe = true;
    box.width = image.width, box.height = image.height;
    return box;
  }, { data: png.toString('base64'), probe });
}

try {
  const started = Date.now();
  const page = await open('?bare');
  const canvas = page.locator('#canvas');
  const bounds = await canvas.boundingBox();
  const restPng = await canvas.screenshot();
  let png = restPng;
  save('rest.png', png);
  const rest = await silhouette(page, png);
  const share = rest.count / (rest.width * rest.height);
  check(share > 0.01 && share < 0.6, `rest: the character is drawn (${(100 * share).toFixed(1)}% of the canvas)`);
  check(rest.top > 0 && rest.bottom < rest.height - 1 && (rest.bottom - rest.top) / rest.height > 0.35,
        `rest: whole and upright (rows ${rest.top}..${rest.bottom} of ${rest.height})`);

  // Press on the left wrist (on the screen's right: the left hand reaches for the point pressed) and drag it to a
  // far point, right of the character and below its shoulder; hold there.
  await reachFar(page, bounds);
  png = await canvas.screenshot();
  save('reach.png', png);
  const reaching = await state(page);
  const reach = await silhouette(page, png, reaching.effector_pixel);
  check(reaching.reaching && reaching.effector === 'hand_l', `reach: the left hand reaches (${reaching.effector})`);
  check(reaching.stretch > 0.15, `reach: the arm is stretched by ${reaching.stretch.toFixed(3)} m (> 0.15)`);
  const wasEmpty = !(await silhouette(page, restPng, reaching.effector_pixel)).probe;
  check(reach.probe && wasEmpty,
        `reach: the hand is drawn where the page says (${reaching.effector_pixel.join(', ')}), ` +
        'where nothing was at rest');
  const further = (reach.right - rest.right) / rest.width;
  check(further > 0.03, `reach: the silhouette reaches ${(100 * further).toFixed(1)}% of the width further right`);

  await page.mouse.up();
  await frames(page, 10, 2000);
  png = await canvas.screenshot();
  save('released.png', png);
  const released = await silhouette(page, png);
  const after = await state(page);
  check(!after.reaching && Math.abs(after.stretch) < 0.02,
        `released: the stretch is back to ${after.stretch.toFixed(4)} m`);
  // The arm keeps the direction the reach turned it to (Character::release lets go of the stretch, not the pose):
  // its length is the rest one again, so the silhouette reaches no further right than at rest, and covers as much.
  check((released.right - rest.right) / rest.width < 0.01 && Math.abs(released.count - rest.count) / rest.count < 0.05,
        `released: the arm has its rest length again (right edge ${released.right} vs ${rest.right} at rest, ` +
        `${released.count} pixels vs ${rest.count})`);
  await page.close();

  // The whole page reaching, as README shows it: the panel, the floor, the reaching arm's lattices.
  const full = await open('');
  await reachFar(full, bounds);
  save('page.png', await full.screenshot());
  check((await state(full)).stretch > 0.15, 'page: the arm stretches on the whole page too');
  await full.mouse.up();

  // The walk, chosen in the panel, plays with the jiggle: its time advances.
  await full.selectOption('#clip', 'walk');
  await frames(full, 2);
  const t0 = (await state(full)).clip_time;
  await frames(full, 5, 300);
  const walking = await state(full);
  check(walking.clip === 'walk' && walking.clip_time !== t0,
        `walk: the panel's clip plays (${t0} s, then ${walking.clip_time} s)`);
  // The panel's reset makes a new character: the page goes on drawing it.
  await full.click('#reset');
  await frames(full, 5);
  const reset = await silhouette(full, await full.locator('#canvas').screenshot());
  check(reset.count > 0.05 * reset.width * reset.height, 'reset: the page draws the new character');
  await full.close();
  check(consoleErrors.length === 0,
        `no error in the page's console${consoleErrors.length ? ': ' + consoleErrors.join('; ') : ''}`);
  console.log(`browser test: ${((Date.now() - started) / 1000).toFixed(1)} s in the browser`);
} catch (error) {
  failures.push(String(error));
  console.error(error);
} finally {
  await browser.close();
  server.close();
}
if (failures.length) {
  console.error(`browser test: ${failures.length} check(s) failed`);
  process.exit(1);
}
