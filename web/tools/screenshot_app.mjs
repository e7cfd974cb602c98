// screenshot_app.mjs: the README's picture of the browser app. Serves the app (web/server.mjs),
// runs the built-in synthetic sample in headless Chromium (npm playwright-core driving Debian's
// /usr/bin/chromium, the browser tests' flags), shows one frame and saves the whole page as a
// PNG, reduced to 256 colours by ffmpeg (palettegen + paletteuse: about 150 KB instead of 400 KB).
//
//   bash scripts/build_web.sh && node web/tools/screenshot_app.mjs [--out docs/img/app.png]
//        [--frame 40] [--width 1280] [--height 800]   (the viewport; the page is taller)

import { spawnSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, rmSync, statSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { createServer } from '../server.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const FLAGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync'];

function parseArgs(argv) {
  const o = { out: join(root, 'docs/img/app.png'), frame: 40, width: 1280, height: 800 };
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    const v = argv[i + 1];
    if (a === '--out' && v) { o.out = resolve(v); ++i; }
    else if (['--frame', '--width', '--height'].includes(a) && Number.isInteger(Number(v)) && Number(v) >= 0) { o[a.slice(2)] = Number(v); ++i; }
    else throw new Error(`unknown or incomplete argument '${a}'\nusage: node web/tools/screenshot_app.mjs [--out FILE.png] [--frame N] [--width W] [--height H]`);
  }
  return o;
}

async function main() {
  const o = parseArgs(process.argv.slice(2));
  const server = createServer(root);
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  const dataDir = mkdtempSync(join(tmpdir(), 'hawor-shot-'));
  let context;
  try {
    const { chromium } = await import('playwright-core');
    context = await chromium.launchPersistentContext(dataDir, {
      executablePath: process.env.HAWOR_CHROMIUM || '/usr/bin/chromium', headless: true, args: FLAGS,
      viewport: { width: o.width, height: o.height },
    });
    const page = context.pages()[0] || await context.newPage();
    const errors = [];
    page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
    page.on('pageerror', (e) => errors.push(e.message));
    await page.goto(`http://127.0.0.1:${server.address().port}/`);
    await page.waitForSelector('body[data-ready="1"]', { timeout: 30000 });
    await page.click('#btn-sample');
    await page.waitForFunction(() => document.body.dataset.busy === '0' && (window.haworApp.result || !document.getElementById('message').hidden), null, { timeout: 180000 });
    const message = await page.evaluate(() => { const m = document.getElementById('message'); return m.hidden ? null : m.textContent; });
    if (message || errors.length) throw new Error(`the sample did not run cleanly: ${message ?? errors.join('; ')}`);
    const T = await page.evaluate(() => window.haworApp.result.frameCount);
    await page.evaluate((f) => window.haworApp.view.setFrame(f), Math.min(o.frame, T - 1));
    await page.waitForTimeout(500);
    const raw = join(dataDir, 'page.png');
    await page.screenshot({ path: raw, fullPage: true });
    mkdirSync(dirname(o.out), { recursive: true });
    const ff = spawnSync('ffmpeg', ['-v', 'error', '-y', '-i', raw, '-vf',
      'split[a][b];[a]palettegen=max_colors=256:stats_mode=full[p];[b][p]paletteuse=dither=sierra2_4a', o.out], { encoding: 'utf8' });
    if (ff.error || ff.status !== 0) throw new Error(`ffmpeg could not reduce the PNG (${ff.error ? ff.error.message : ff.stderr.trim()})`);
    process.stderr.write(`[screenshot_app] ${o.out}: ${o.width} px wide, frame ${Math.min(o.frame, T - 1) + 1}/${T}, ${(statSync(raw).size / 1024).toFixed(0)} KB -> ${(statSync(o.out).size / 1024).toFixed(0)} KB\n`);
  } finally {
    if (context) await context.close();
    server.close();
    rmSync(dataDir, { recursive: true, force: true });
  }
}

main().catch((e) => {
  process.stderr.write(`screenshot_app: ${e.message}\n`);
  process.exitCode = 1;
});
