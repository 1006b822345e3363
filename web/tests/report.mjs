// The HTML reports of `urdf-dh calibrate --report` and `urdf-dh cpa --report` opened as a person
// opens them, in Debian's chromium driven by playwright-core: a simulated UR5 set (two samples
// moved by 4 mm: outliers) calibrated with --effects auto, and a simulated circle-point set,
// each page served from localhost. Checks: no console error, no request at all besides the page
// itself (the page is self-contained; anything else is aborted and counted), every section there,
// every plot drawn at a nonzero size with its dots, the outliers listed, the figures those of the
// text report. Also opened from file:// (as a person double-clicks it). Prints 'N passed,
// N failed' last; exits 1 on any failure.
//
// Usage: node web/tests/report.mjs CLI_BINARY   (web/test.sh calls it after browser.mjs)
// Env: CHROMIUM (default /usr/bin/chromium), SCREENSHOTS=dir (save a screenshot of each page).
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { launch, suite } from './harness.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..', '..');
const CLI = path.resolve(process.argv[2] || path.join(ROOT, 'target/debug/urdf-dh'));
const SHOTS = process.env.SCREENSHOTS || '';
const UR5 = path.join(ROOT, 'fixtures/robots/ur5/vendor.yaml');

const { test, assert, run } = suite();

function cli(args) {
  const r = spawnSync(CLI, args, { cwd: ROOT, encoding: 'utf8' });
  if (r.status !== 0 && r.status !== 1) throw new Error(`urdf-dh ${args.join(' ')}: exit ${r.status}\n${r.stderr}`);
  return r.stdout;
}

/// Moves the `column` of the data lines `offsets` after the header by `delta`.
function moveSamples(file, column, offsets, delta) {
  const lines = fs.readFileSync(file, 'utf8').split('\n');
  const header = lines.findIndex((l) => l.startsWith('shoulder_pan_joint'));
  const k = lines[header].split(',').indexOf(column);
  for (const o of offsets) {
    const cells = lines[header + o].split(',');
    cells[k] = String(Number(cells[k]) + delta);
    lines[header + o] = cells.join(',');
  }
  fs.writeFileSync(file, lines.join('\n'));
  return offsets.map((o) => header + o + 1);
}

async function main() {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'urdf-dh-report-'));
  const data = path.join(dir, 'ur5.csv');
  cli(['simulate', '--model', UR5, '--poses', '60', '--noise', '5e-5', '--targets', '2', '--seed', '3',
    '--validation', '0.25', '--error', 'elbow_joint.a=5e-4', '--out', data]);
  const moved = moveSamples(data, 'x', [12, 43], 0.004);
  const calibrateHtml = path.join(dir, 'calibrate.html');
  const text = cli(['calibrate', '--model', UR5, '--data', data, '--effects', 'auto', '--report', calibrateHtml]);
  const cpaData = path.join(dir, 'cpa.csv');
  cli(['simulate', '--model', UR5, '--poses', '8', '--cpa', '--noise', '2e-5', '--seed', '4', '--out', cpaData]);
  const cpaMoved = moveSamples(cpaData, 'z', [12], 0.003);
  const cpaHtml = path.join(dir, 'cpa.html');
  cli(['cpa', cpaData, '--model', UR5, '--report', cpaHtml]);

  const server = http.createServer((req, res) => {
    const name = path.basename(new URL(req.url, 'http://localhost').pathname);
    const file = path.join(dir, name);
    if (!name.endsWith('.html') || !fs.existsSync(file)) {
      res.writeHead(404);
      res.end();
      return;
    }
    res.writeHead(200, { 'content-type': 'text/html; charset=utf-8' });
    res.end(fs.readFileSync(file));
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  const origin = `http://127.0.0.1:${server.address().port}`;
  const { context, profile } = await launch('urdf-dh-report-profile-');
  // Every request but the page's own is aborted and counted: the page needs none.
  const requests = [];
  await context.route('**/*', (route) => {
    const u = route.request().url();
    if ((u.startsWith(origin) || u.startsWith('file://')) && u.endsWith('.html')) return route.continue();
    requests.push(u);
    return route.abort();
  });
  const page = context.pages()[0] || (await context.newPage());
  const consoleErrors = [];
  page.on('console', (m) => {
    if (m.type() === 'error' || m.type() === 'warning') consoleErrors.push(`${m.type()}: ${m.text()}`);
  });
  page.on('pageerror', (e) => consoleErrors.push(String(e)));

  /// The sections' ids and each SVG's rendered size and dot count.
  async function inspect() {
    return page.evaluate(() => ({
      sections: [...document.querySelectorAll('section[data-testid]')].map((s) => s.dataset.testid),
      svgs: [...document.querySelectorAll('svg')].map((s) => {
        const r = s.getBoundingClientRect();
        const dots = [...s.querySelectorAll('path.cal:not(.key), path.val:not(.key)')].reduce((n, p) => n + (p.getAttribute('d').match(/M/g) || []).length, 0);
        return { w: r.width, h: r.height, dots, rings: s.querySelectorAll('g.out circle').length };
      }),
      title: document.title,
    }));
  }

  await test('the calibration report opens with every section and its plots drawn', async () => {
    await page.goto(`${origin}/calibrate.html`);
    const r = await inspect();
    for (const s of ['summary', 'steps', 'residuals', 'outliers', 'diagnosis', 'parameters', 'correlations', 'verdict', 'settings', 'provenance']) {
      assert(r.sections.includes(s), `no section ${s}: ${r.sections}`);
    }
    // The step bars, two pose-order plots and one per joint (six).
    assert(r.svgs.length === 1 + 2 + 6, `${r.svgs.length} plots`);
    for (const s of r.svgs) assert(s.w > 100 && s.h > 50, `a plot of ${s.w} x ${s.h}`);
    for (const s of r.svgs.slice(1)) {
      assert(s.dots === 120, `${s.dots} dots, expected 120`);
      assert(s.rings === 2, `${s.rings} outlier rings, expected 2`);
    }
    if (SHOTS) await page.screenshot({ path: path.join(SHOTS, 'report-calibrate.png'), fullPage: true });
  });

  await test('the calibration report lists the outliers and the text report\'s RMS', async () => {
    const lines = await page.$$eval('[data-testid=outliers] tbody tr', (rows) => rows.map((r) => r.cells[0].textContent));
    assert(JSON.stringify(lines) === JSON.stringify(moved.map(String)), `outliers at ${lines}, moved ${moved}`);
    const geometric = await page.$$eval('[data-testid=steps] tbody tr', (rows) =>
      rows.map((r) => [...r.cells].map((c) => c.textContent)).find((c) => c[0] === 'geometric'));
    const textRms = Number(text.split('\n').find((l) => l.startsWith('geometric')).trim().split(/\s+/)[3]);
    assert(Math.abs(Number(geometric[4]) - textRms * 1e3) < 1e-9, `page ${geometric[4]} mm, text ${textRms} m`);
    const verdict = await page.textContent('[data-testid=summary] .big');
    assert(text.includes(`verdict: ${verdict}`), `summary '${verdict}' not in the text report`);
  });

  await test('the cpa report opens with its sections, plots and the point left out', async () => {
    await page.goto(`${origin}/cpa.html`);
    const r = await inspect();
    for (const s of ['summary', 'sweeps', 'joints', 'residuals', 'outliers', 'table', 'proof', 'provenance']) {
      assert(r.sections.includes(s), `no section ${s}: ${r.sections}`);
    }
    assert(r.svgs.length === 12, `${r.svgs.length} plots, expected two per joint`);
    for (const s of r.svgs) assert(s.w > 100 && s.h > 50 && s.dots > 0, `a plot of ${s.w} x ${s.h}, ${s.dots} dots`);
    assert(r.svgs.reduce((n, s) => n + s.rings, 0) === 1, 'one ring');
    const left = await page.$$eval('[data-testid=outliers] tbody tr', (rows) => rows.map((r) => r.cells[1].textContent));
    assert(JSON.stringify(left) === JSON.stringify(cpaMoved.map(String)), `left out ${left}, moved ${cpaMoved}`);
    if (SHOTS) await page.screenshot({ path: path.join(SHOTS, 'report-cpa.png'), fullPage: true });
  });

  await test('the report opens from file:// as well', async () => {
    await page.goto(`file://${calibrateHtml}`);
    const r = await inspect();
    assert(r.sections.length >= 10 && r.svgs.every((s) => s.w > 100), `${r.sections}`);
  });

  await test('no console errors or warnings', async () => {
    assert(consoleErrors.length === 0, consoleErrors.join('\n'));
  });

  await test('no request besides the pages themselves', async () => {
    assert(requests.length === 0, requests.join('\n'));
  });

  await context.close();
  server.close();
  fs.rmSync(dir, { recursive: true, force: true });
  fs.rmSync(profile, { recursive: true, force: true });
}

run(main);
