// The page tested as a person uses it, in Debian's chromium driven by playwright-core: served
// from localhost, a URDF uploaded through the file input, the table and the verdict read, a
// slider moved, downloads compared with the CLI's bytes, the JS API compared with the CLI on
// every chain of ../shared/robots, the 3-D canvas checked for a picture, no console error, no
// request leaving localhost. Prints 'N passed, N failed' last; exits 1 on any failure.
//
// Usage: node web/tests/browser.mjs CLI_BINARY   (web/test.sh builds both and calls this)
// Env: CHROMIUM (default /usr/bin/chromium), SCREENSHOTS=dir (save screenshots there).
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { launch, suite } from './harness.mjs';

const WEB = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const ROOT = path.resolve(WEB, '..');
const DIST = path.join(WEB, 'dist');
const SHARED = path.resolve(ROOT, '..', 'shared');
const CLI = path.resolve(process.argv[2] || path.join(ROOT, 'target/debug/urdf-dh'));
const SHOTS = process.env.SCREENSHOTS || '';
const PANDA = path.join(ROOT, 'fixtures/robots/franka_panda');

const { test, assert, run, finish } = suite();
const figures = [];


function assertEqual(got, want, what) {
  if (got !== want) {
    const g = String(got);
    const w = String(want);
    let i = 0;
    while (i < g.length && g[i] === w[i]) i++;
    throw new Error(`${what}: differs at character ${i}:\n  got  ${JSON.stringify(g.slice(Math.max(0, i - 60), i + 60))}\n  want ${JSON.stringify(w.slice(Math.max(0, i - 60), i + 60))}`);
  }
}

// The CLI takes sin, cos and atan2 from the platform's libm (glibc); WebAssembly from Rust's
// own (musl's algorithms). Their last bits differ, and so do the last digits of what is computed
// from them: the proofs' measured deviations (float noise, 1e-16 for an exact table), a check's
// FK deviation of a mismatched sheet. So: every byte that is not part of a number must be the
// same, and every number the same or within FLOAT_ABS + FLOAT_REL * |value| (a wrong value, a
// wrong sample count or seed is far outside). Counts how many outputs were byte for byte equal.
// A check's FK deviation of a mismatched sheet follows a least-squares fit of the free base and
// tool, which carries those last bits further: the numbers printed after an `error` key or
// word (`max_position_error`, `max orientation error`) get DEVIATION_REL.
const FLOAT_ABS = 1e-13;
const FLOAT_REL = 1e-12;
const DEVIATION_REL = 1e-6;
const NUMBER = /-?\d+(?:\.\d+)?(?:e[+-]?\d+)?/gi;
const sameness = { exact: 0, noise: 0 };

// The JSON's lengths and angles are printed rounded to 12 decimals (a picometre, a picoradian:
// dh_workflows::units, decimals): a last-bit difference can flip the last printed digit, so a
// number may also differ by one unit of that rounding, PRINTED, and no more.
const PRINTED = 1e-12;

// An `"rpy": [roll, pitch, yaw]` triple is a rotation, R = Rz(yaw) Ry(pitch) Rx(roll) (URDF's
// convention), and is compared as one: near gimbal lock (|pitch| -> pi/2) roll and yaw are
// ill-conditioned (their last-bit differences grow as 1/cos(pitch): 1.8e-11 rad at a pitch of
// 1.5707897 in an SDFormat chain) while the rotation they give is not. The matrices' entries
// must agree within FLOAT_ABS + FLOAT_REL, which holds a wrong angle to the same standard as
// any other number.
function rpyMatrix([r, p, y]) {
  const [cr, sr, cp, sp, cy, sy] = [Math.cos(r), Math.sin(r), Math.cos(p), Math.sin(p), Math.cos(y), Math.sin(y)];
  return [
    cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
    sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
    -sp, cp * sr, cp * cr,
  ];
}

function sameRotation(got, want) {
  const [g, w] = [rpyMatrix(got), rpyMatrix(want)];
  // The three angles' printed rounding moves an entry by at most 3 PRINTED.
  return g.every((x, i) => Math.abs(x - w[i]) <= FLOAT_ABS + FLOAT_REL + 3 * PRINTED);
}

function assertSameOutput(got, want, what) {
  if (got === want) {
    sameness.exact++;
    return;
  }
  const words = (t) => t.split(NUMBER);
  const numbers = (t) => (t.match(NUMBER) || []).map(Number);
  const [gw, ww, gn, wn] = [words(got), words(want), numbers(got), numbers(want)];
  const shapes = gw.length === ww.length && gw.every((w, i) => w === ww[i]) && gn.length === wn.length;
  let close = shapes;
  for (let i = 0; close && i < gn.length; i++) {
    if (/"rpy":\s*\[\s*$/.test(gw[i]) && i + 2 < gn.length) {
      close = sameRotation(gn.slice(i, i + 3), wn.slice(i, i + 3));
      i += 2;
      continue;
    }
    const rel = /error\W*$/.test(gw[i]) ? DEVIATION_REL : FLOAT_REL;
    close = Math.abs(gn[i] - wn[i]) <= FLOAT_ABS + rel * Math.max(Math.abs(gn[i]), Math.abs(wn[i])) + PRINTED * (1 + 1e-9);
  }
  if (close) {
    sameness.noise++;
    return;
  }
  assertEqual(got, want, what);
}

// `testid`'s text now ('' while the page has no such element), and once it differs from `before`: a dropped file is read and processed after
// setInputFiles returns, so the element is read when the page has updated it (or after 10 s,
// when the assertion on the returned text says what stayed).
async function currentText(page, testid) {
  return await page.evaluate((q) => document.querySelector(q)?.textContent ?? '', `[data-testid="${testid}"]`);
}

async function changedText(page, testid, before) {
  const sel = `[data-testid="${testid}"]`;
  await page
    .waitForFunction(([q, b]) => (document.querySelector(q)?.textContent ?? '') !== b, [sel, before], { timeout: 10000 })
    .catch(() => {});
  return await page.getByTestId(testid).textContent();
}

// The CLI run in `cwd` (so that file names print as the page names them); stdout, stderr, code.
function cli(args, cwd, env = undefined) {
  const r = spawnSync(CLI, args, { cwd, encoding: 'utf8', maxBuffer: 64 << 20, env: env ? { ...process.env, ...env } : undefined });
  if (r.error) throw r.error;
  return { out: r.stdout, err: r.stderr, code: r.status };
}

// A static server of web/dist on 127.0.0.1 (an ephemeral port).
function serve() {
  const types = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css', '.wasm': 'application/wasm', '.json': 'application/json', '.urdf': 'application/xml', '.yaml': 'text/yaml' };
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://localhost');
    let file = path.normalize(path.join(DIST, decodeURIComponent(url.pathname)));
    if (!file.startsWith(DIST)) {
      res.writeHead(403).end();
      return;
    }
    if (url.pathname.endsWith('/')) file = path.join(file, 'index.html');
    fs.readFile(file, (err, data) => {
      if (err) {
        res.writeHead(404).end();
        return;
      }
      res.writeHead(200, { 'content-type': types[path.extname(file)] || 'application/octet-stream' });
      res.end(data);
    });
  });
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve(server)));
}

// Variance of the luminance of a PNG screenshot, decoded by the page's own canvas.
async function pngVariance(page, png) {
  return await page.evaluate(async (b64) => {
    const img = new Image();
    img.src = `data:image/png;base64,${b64}`;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width;
    c.height = img.height;
    const ctx = c.getContext('2d');
    ctx.drawImage(img, 0, 0);
    const d = ctx.getImageData(0, 0, c.width, c.height).data;
    let sum = 0;
    let sq = 0;
    const n = d.length / 4;
    for (let i = 0; i < d.length; i += 4) {
      const y = 0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2];
      sum += y;
      sq += y * y;
    }
    const mean = sum / n;
    return sq / n - mean * mean;
  }, png.toString('base64'));
}

// Chains of ../shared/robots as the CLI's corpus tests take them: root to every leaf with a
// moving joint on the way.
async function sharedChains(page) {
  const dirs = fs.readdirSync(path.join(SHARED, 'robots')).filter((d) => fs.existsSync(path.join(SHARED, 'robots', d, 'robot.urdf'))).sort();
  const chains = [];
  for (const d of dirs) {
    const file = path.join(SHARED, 'robots', d, 'robot.urdf');
    const text = fs.readFileSync(file, 'utf8');
    const leaves = await page.evaluate((t) => {
      const tree = window.urdfDh.tree(t);
      const parents = new Set(tree.links.map((l) => l.parent).filter((p) => p !== null));
      return { root: tree.root, leaves: tree.links.map((l) => l.name).filter((n) => !parents.has(n)) };
    }, text);
    for (const leaf of leaves.leaves) chains.push({ dir: d, file, text, base: leaves.root, tip: leaf });
  }
  return chains;
}

async function main() {
  assert(fs.existsSync(path.join(DIST, 'index.html')), `no ${DIST}/index.html: run web/build.sh first`);
  assert(fs.existsSync(CLI), `no CLI binary at ${CLI}`);
  const server = await serve();
  const origin = `http://127.0.0.1:${server.address().port}`;
  const downloads = fs.mkdtempSync(path.join(os.tmpdir(), 'urdf-dh-downloads-'));
  // A fresh profile: playwright passes it as --user-data-dir.
  const { context, profile } = await launch('urdf-dh-chromium-', ['--use-angle=swiftshader', '--enable-unsafe-swiftshader'], {
    downloadsPath: downloads,
    acceptDownloads: true,
    viewport: { width: 1500, height: 900 },
  });
  const outside = [];
  await context.route('**/*', (route) => {
    const u = new URL(route.request().url());
    if (['http:', 'https:', 'ws:', 'wss:'].includes(u.protocol) && u.hostname !== '127.0.0.1' && u.hostname !== 'localhost') {
      outside.push(u.href);
      return route.abort();
    }
    return route.continue();
  });
  const page = context.pages()[0] || (await context.newPage());
  const consoleErrors = [];
  page.on('console', (m) => {
    if (m.type() === 'error') consoleErrors.push(m.text());
  });
  page.on('pageerror', (e) => consoleErrors.push(String(e)));

  await test('the page loads and says a robot file stays on the machine', async () => {
    await page.goto(`${origin}/`);
    await page.waitForSelector('body[data-ready="true"]', { timeout: 20000 });
    const ready = await page.evaluate(() => performance.now());
    figures.push(`page load to ready (wasm compiled, gallery listed), as the test saw it: ${ready.toFixed(0)} ms`);
    const privacy = await page.getByTestId('privacy').textContent();
    assert(/never leaves this machine/.test(privacy), `privacy note: ${privacy}`);
  });

  const pandaUrdf = path.join(PANDA, 'robot.urdf');
  const cliJson = cli(['extract', 'robot.urdf', '--format', 'json'], PANDA).out;
  const cliText = cli(['extract', 'robot.urdf'], PANDA).out;

  await test('upload the Panda: the table and the verdict are the CLI\'s', async () => {
    await page.getByTestId('urdf-file').setInputFiles(pandaUrdf);
    await page.waitForFunction(() => document.querySelector('[data-testid="verdict"]').textContent.length > 0);
    const rows = await page.locator('[data-testid="dh-table"] tbody tr').all();
    const sheet = JSON.parse(cliJson);
    assertEqual(rows.length, sheet.joints.length, 'rows');
    for (let i = 0; i < rows.length; i++) {
      const cells = await rows[i].locator('td').allTextContents();
      const j = sheet.joints[i];
      assertEqual(cells[1], j.name, `row ${i + 1} joint`);
      assertEqual(cells.slice(3, 7).join(' '), [j.theta, j.d, j.a, j.alpha].map((v) => v.toFixed(6)).join(' '), `row ${i + 1} theta d a alpha`);
    }
    const verdict = await page.getByTestId('verdict').textContent();
    const want = cliText.trimEnd().split('\n').pop();
    assertSameOutput(verdict, want, 'verdict');
    assert(/: PASS$/.test(verdict), `verdict: ${verdict}`);
    if (SHOTS) await page.screenshot({ path: path.join(SHOTS, 'panda.png') });
    const title = await page.getByTestId('title').textContent();
    assertEqual(title, cliText.split('\n')[0], 'title line');
  });

  await test('a slider moves the URDF and DH frames together', async () => {
    const before = await page.evaluate(() => document.querySelector('[data-testid="view3d"] canvas').toDataURL());
    const slider = page.getByTestId('slider-1');
    const box = await slider.boundingBox();
    await page.mouse.click(box.x + box.width * 0.8, box.y + box.height / 2);
    const value = await slider.inputValue();
    assert(Math.abs(Number(value)) > 0.3, `slider value ${value}`);
    const gap = await page.getByTestId('tip-gap').textContent();
    const m = /([0-9.e+-]+) m apart/.exec(gap);
    assert(m && Number(m[1]) < 1e-9, `tip gap after the move: ${gap}`);
    const after = await page.evaluate(() => document.querySelector('[data-testid="view3d"] canvas').toDataURL());
    assert(before !== after, 'the picture did not change');
  });

  await test('urdfDh.fk: the URDF and the DH table put the tip at the same pose', async () => {
    const text = fs.readFileSync(pandaUrdf, 'utf8');
    const worst = await page.evaluate((t) => {
      let worst = 0;
      for (let k = 0; k < 20; k++) {
        const q = Array.from({ length: 7 }, (_, i) => Math.sin(3.7 * k + i) * 1.5);
        for (const convention of ['standard', 'modified']) {
          const s = window.urdfDh.fk(t, { convention }, q);
          if (s.dh.length !== 8 || s.urdf.length !== 8 || s.axes.length !== 7 || s.normals.length !== 7) throw new Error('counts');
          const u = s.urdf[7];
          for (let e = 0; e < 16; e++) worst = Math.max(worst, Math.abs(u[e] - s.dh_tip[e]));
        }
      }
      return worst;
    }, text);
    assert(worst < 1e-12, `tip poses differ by ${worst}`);
  });

  await test('click a row highlights it', async () => {
    await page.locator('[data-testid="dh-table"] tbody tr').nth(2).click();
    const cls = await page.locator('[data-testid="dh-table"] tbody tr').nth(2).getAttribute('class');
    assert(/selected/.test(cls || ''), `row class: ${cls}`);
  });

  await test('the 3-D canvas draws (screenshot variance)', async () => {
    const png = await page.getByTestId('view3d').screenshot();
    if (SHOTS) fs.writeFileSync(path.join(SHOTS, 'view3d.png'), png);
    const v = await pngVariance(page, png);
    assert(v > 50, `luminance variance ${v.toFixed(1)}: blank?`);
  });

  for (const [format, ext] of [['yaml', 'yaml'], ['json', 'json'], ['csv', 'csv'], ['markdown', 'md']]) {
    await test(`download ${format}: the CLI's bytes`, async () => {
      const [dl] = await Promise.all([page.waitForEvent('download'), page.getByTestId(`download-${format}`).click()]);
      assertEqual(dl.suggestedFilename(), `panda.dh.${ext}`, 'file name');
      const got = fs.readFileSync(await dl.path(), 'utf8');
      assertSameOutput(got, cli(['extract', 'robot.urdf', '--format', format], PANDA).out, format);
    });
  }

  await test('download the DH-built URDF: the CLI\'s to-urdf bytes', async () => {
    const [dl] = await Promise.all([page.waitForEvent('download'), page.getByTestId('download-urdf').click()]);
    const got = fs.readFileSync(await dl.path(), 'utf8');
    const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'urdf-dh-sheet-'));
    fs.writeFileSync(path.join(tmp, 'panda.dh.yaml'), cli(['extract', pandaUrdf, '--format', 'yaml'], PANDA).out);
    const want = cli(['to-urdf', 'panda.dh.yaml'], tmp);
    assertEqual(want.code, 0, 'to-urdf exit code');
    assertEqual(got, want.out, 'urdf');
    assert(/: PASS -->/.test(got), 'the proof comment');
  });

  await test('modified convention and mm/deg: the table follows, the JSON is the CLI\'s', async () => {
    await page.getByTestId('convention-select').selectOption('modified');
    await page.getByTestId('length-unit').selectOption('mm');
    await page.getByTestId('angle-unit').selectOption('deg');
    const [dl] = await Promise.all([page.waitForEvent('download'), page.getByTestId('download-json').click()]);
    const got = fs.readFileSync(await dl.path(), 'utf8');
    const want = cli(['extract', 'robot.urdf', '--format', 'json', '--convention', 'modified', '--length-unit', 'mm', '--angle-unit', 'deg'], PANDA).out;
    assertSameOutput(got, want, 'json');
    const verdict = await page.getByTestId('verdict').textContent();
    const text = cli(['extract', 'robot.urdf', '--convention', 'modified', '--length-unit', 'mm', '--angle-unit', 'deg'], PANDA).out;
    assertSameOutput(verdict, text.trimEnd().split('\n').pop(), 'verdict');
    const header = await page.locator('[data-testid="dh-table"] thead').textContent();
    assert(/d \[mm\]/.test(header) && /alpha \[deg\]/.test(header), `header: ${header}`);
    await page.getByTestId('convention-select').selectOption('standard');
    await page.getByTestId('length-unit').selectOption('m');
    await page.getByTestId('angle-unit').selectOption('rad');
  });

  await test('check the vendor sheet: MATCH, and the JSON is the CLI\'s', async () => {
    const before = await currentText(page, 'check-verdict');
    await page.getByTestId('sheet-file').setInputFiles(path.join(PANDA, 'vendor.yaml'));
    const head = await changedText(page, 'check-verdict', before);
    const want = cli(['check', 'robot.urdf', '--sheet', 'vendor.yaml', '--format', 'json'], PANDA);
    const report = JSON.parse(want.out);
    assertEqual(/^MATCH/.test(head), report.matches, `check verdict '${head}'`);
    const urdf = fs.readFileSync(pandaUrdf, 'utf8');
    const sheet = fs.readFileSync(path.join(PANDA, 'vendor.yaml'), 'utf8');
    const got = await page.evaluate(([u, s]) => window.urdfDh.check(u, s, { sheet_name: 'vendor.yaml' }), [urdf, sheet]);
    assertSameOutput(got, want.out, 'check json');
  });

  await test('check a sheet with one wrong d: MISMATCH, the joint and parameter highlighted', async () => {
    const sheet = fs.readFileSync(path.join(PANDA, 'vendor.yaml'), 'utf8');
    const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'urdf-dh-wrong-'));
    const wrong = sheet.replace(/d: 0\.316/, 'd: 0.326');
    assert(wrong !== sheet, 'the fixture changed: no "d: 0.316" in vendor.yaml');
    fs.writeFileSync(path.join(tmp, 'wrong.yaml'), wrong);
    const before = await currentText(page, 'check-verdict');
    await page.getByTestId('sheet-file').setInputFiles(path.join(tmp, 'wrong.yaml'));
    const head = await changedText(page, 'check-verdict', before);
    assert(/^MISMATCH/.test(head), `check verdict '${head}'`);
    const marked = await page.locator('[data-testid="dh-table"] td.diff').evaluateAll((tds) => tds.map((td) => `${td.parentElement.dataset.joint} ${td.dataset.param}`));
    const want = JSON.parse(cli(['check', pandaUrdf, '--sheet', path.join(tmp, 'wrong.yaml'), '--format', 'json'], PANDA).out);
    const named = want.differences.filter((d) => d.joint && ['a', 'alpha', 'd', 'theta'].includes(d.parameter)).map((d) => `${d.joint} ${d.parameter}`);
    assert(named.length > 0, 'the CLI named no joint parameter');
    assertEqual(marked.join(', '), named.join(', '), 'highlighted cells');
    if (SHOTS) await page.screenshot({ path: path.join(SHOTS, 'mismatch.png') });
  });

  await test('a broken URDF: the CLI\'s error on the page, no table', async () => {
    const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'urdf-dh-bad-'));
    fs.writeFileSync(path.join(tmp, 'bad.urdf'), '<robot name="r"><link name="a"/><joint name="j" type="revolute"><parent link="a"/><child link="nowhere"/></joint></robot>');
    const before = await currentText(page, 'error');
    await page.getByTestId('urdf-file').setInputFiles(path.join(tmp, 'bad.urdf'));
    const shown = await changedText(page, 'error', before);
    const want = cli(['extract', 'bad.urdf'], tmp);
    assertEqual(want.code, 2, 'CLI exit code');
    const first = want.err.split('\n').find((l) => l.startsWith('urdf-dh: error: '));
    assertEqual(shown.split('\n')[0], first.replace('urdf-dh: error: ', 'error: '), 'error line');
    assertEqual(await page.locator('[data-testid="dh-table"] tbody tr').count(), 0, 'rows');
  });

  await test('the gallery: every robot extracts with PASS', async () => {
    const names = await page.locator('[data-testid="gallery"] button').allTextContents();
    assert(names.length >= 5, `gallery: ${names}`);
    const formats = new Set();
    for (let i = 0; i < names.length; i++) {
      const before = await page.evaluate(() => window.urdfDh.loads);
      await page.locator('[data-testid="gallery"] button').nth(i).click();
      await page.waitForFunction((n) => window.urdfDh.loads > n, before);
      const verdict = await page.getByTestId('verdict').textContent();
      assert(/: PASS$/.test(verdict), `${names[i]}: ${verdict} ${await page.getByTestId('error').textContent()}`);
      formats.add(await page.getByTestId('format').textContent());
    }
    assert(formats.has('MJCF') && formats.has('URDF'), `gallery formats: ${[...formats]}`);
  });

  await test('the gallery\'s xacro package: the CLI\'s JSON, with its argument', async () => {
    const i = (await page.locator('[data-testid="gallery"] button').allTextContents()).indexOf('demo arm xacro');
    assert(i >= 0, 'a xacro gallery entry');
    const before = await page.evaluate(() => window.urdfDh.loads);
    await page.locator('[data-testid="gallery"] button').nth(i).click();
    await page.waitForFunction((n) => window.urdfDh.loads > n, before);
    assertEqual(await page.getByTestId('xacro-args').inputValue(), 'reach:=long', 'xacro args');
    const pkg = path.join(ROOT, 'fixtures/xacro/demo_arm_description');
    const want = cli(['extract', 'arm.urdf.xacro', '--xacro-arg', 'reach:=long', '--package', `demo_arm_description=${pkg}`, '--format', 'text'], path.join(pkg, 'urdf'));
    assertEqual(want.code, 0, `CLI: ${want.err}`);
    const lines = want.out.trimEnd().split('\n');
    assertEqual(await page.getByTestId('title').textContent(), lines[0], 'title line');
    assertSameOutput(await page.getByTestId('verdict').textContent(), lines[lines.length - 1], 'verdict');
    // Another argument: the table follows (the upper arm is 0.45 m instead of 0.6 m).
    const a = async () => (await page.locator('[data-testid="dh-table"] tbody tr').nth(1).locator('td[data-param="a"]').textContent());
    assertEqual(await a(), '0.600000', 'a of joint2, reach:=long');
    const again = await page.evaluate(() => window.urdfDh.loads);
    await page.getByTestId('xacro-args').fill('reach:=short');
    await page.getByTestId('xacro-args').dispatchEvent('change');
    await page.waitForFunction((n) => window.urdfDh.loads > n, again);
    assertEqual(await a(), '0.450000', 'a of joint2, reach:=short');
  });

  await test('a xacro file without its package: the error names the package', async () => {
    const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'urdf-dh-xacro-'));
    fs.copyFileSync(path.join(ROOT, 'fixtures/xacro/demo_arm_description/urdf/arm.urdf.xacro'), path.join(tmp, 'arm.urdf.xacro'));
    await page.getByTestId('urdf-file').setInputFiles(path.join(tmp, 'arm.urdf.xacro'));
    await page.waitForFunction(() => !document.querySelector('[data-testid="error"]').hidden);
    const shown = await page.getByTestId('error').textContent();
    assert(/package 'demo_arm_description' not found/.test(shown), `error: ${shown}`);
    assertEqual(await page.locator('[data-testid="dh-table"] tbody tr').count(), 0, 'rows');
  });

  await test('several files dropped: the robot file is chosen, its includes read from the others', async () => {
    const dir = path.join(ROOT, 'fixtures/xacro/demo_arm_description');
    const list = ['urdf/segment.xacro', 'config/links.yaml', 'package.xml', 'urdf/arm.urdf.xacro'].map((p) => ({ path: `/demo_arm_description/${p}`, text: fs.readFileSync(path.join(dir, p), 'utf8') }));
    const before = await page.evaluate(() => window.urdfDh.loads);
    await page.evaluate((l) => window.urdfDh.loadFiles(l), list);
    await page.waitForFunction((n) => window.urdfDh.loads > n, before);
    assertEqual(await page.getByTestId('robot-file').inputValue(), '/demo_arm_description/urdf/arm.urdf.xacro', 'robot file chosen');
    const verdict = await page.getByTestId('verdict').textContent();
    assert(/: PASS$/.test(verdict), `verdict: ${verdict} ${await page.getByTestId('error').textContent()}`);
  });

  await test('drop to table for the Panda: timed in the page', async () => {
    const text = fs.readFileSync(pandaUrdf, 'utf8');
    const times = await page.evaluate(async (t) => {
      const out = [];
      for (let k = 0; k < 15; k++) {
        const t0 = performance.now();
        await window.urdfDh.load(t, 'robot.urdf');
        out.push(performance.now() - t0);
      }
      return out;
    }, text);
    times.sort((a, b) => a - b);
    const median = times[Math.floor(times.length / 2)];
    figures.push(`drop to table (Panda: tree, one extraction, JSON and text proved (the robot file's FK once), warnings, FK, DOM, 3-D), median of 15: ${median.toFixed(1)} ms (min ${times[0].toFixed(1)}, max ${times[times.length - 1].toFixed(1)})`);
    // What the page did per drop before (four extractions: JSON, text, warnings, the 3-D
    // scene's; two proofs each computing the robot file's FK), the same library calls timed
    // without the DOM: the part of a drop that extracting once saves.
    const [oldWay, newWay] = await page.evaluate((t) => {
      const o = { name: 'robot.urdf' };
      const time = (f) => {
        const ts = [];
        for (let k = 0; k < 15; k++) {
          const t0 = performance.now();
          f();
          ts.push(performance.now() - t0);
        }
        ts.sort((a, b) => a - b);
        return ts[7];
      };
      const oldWay = time(() => {
        window.urdfDh.tree(t, o);
        window.urdfDh.extract(t, { ...o, format: 'json' });
        window.urdfDh.extract(t, { ...o, format: 'text' });
        window.urdfDh.warnings(t, o);
        window.urdfDh.fk(t, o, [0, 0, 0, 0, 0, 0, 0]);
      });
      const newWay = time(() => {
        window.urdfDh.tree(t, o);
        const r = window.urdfDh.robot(t, o);
        r.output('json');
        r.output('text');
        r.warnings();
        r.fk(new Float64Array(7));
        r.free();
      });
      return [oldWay, newWay];
    }, text);
    figures.push(`Panda, library calls of a drop without the DOM, median of 15: ${oldWay.toFixed(1)} ms as before (4 extractions, 2 proofs with their own FK) vs ${newWay.toFixed(1)} ms now (1 extraction, 2 proofs sharing the robot file's FK)`);
    const api = await page.evaluate((t) => {
      const t0 = performance.now();
      for (let k = 0; k < 10; k++) window.urdfDh.extract(t, { format: 'json' });
      return (performance.now() - t0) / 10;
    }, text);
    figures.push(`urdfDh.extract (Panda, JSON, 1000-sample proof): ${api.toFixed(1)} ms`);
    assert(median < 500, `drop to table took ${median} ms`);
  });

  if (SHOTS) {
    await page.locator('[data-testid="gallery"] button').first().click();
    await page.waitForFunction(() => document.querySelector('[data-testid="gallery"] button.active') !== null);
    await page.getByTestId('gallery-sheet').click();
    await page.getByTestId('slider-1').fill('0.6');
    await page.getByTestId('slider-2').fill('-0.5');
    await page.locator('[data-testid="dh-table"] tbody tr').nth(1).click();
    await page.screenshot({ path: path.join(SHOTS, 'page.png') });
  }

  if (fs.existsSync(path.join(SHARED, 'robots'))) {
    await test('the JS API\'s JSON is the CLI\'s for every chain of ../shared/robots', async () => {
      const chains = await sharedChains(page);
      let compared = 0;
      const bad = [];
      for (const c of chains) {
        for (const convention of ['standard', 'modified']) {
          const want = cli(['extract', 'robot.urdf', '--base', c.base, '--tip', c.tip, '--convention', convention, '--format', 'json'], path.dirname(c.file));
          const got = await page.evaluate(([t, o]) => {
            try {
              return { out: window.urdfDh.extract(t, o) };
            } catch (e) {
              return { err: e.message };
            }
          }, [c.text, { base: c.base, tip: c.tip, convention }]);
          if (want.code === 2) {
            const first = want.err.split('\n').find((l) => l.startsWith('urdf-dh: error: '));
            if (got.err === undefined || `urdf-dh: error: ${got.err.split('\n')[0]}` !== first) bad.push(`${c.dir} ${c.tip} ${convention}: CLI ${first}, page ${got.err ?? 'no error'}`);
          } else {
            try {
              assertSameOutput(got.out, want.out, 'json');
            } catch (e) {
              bad.push(`${c.dir} ${c.tip} ${convention}: ${e.message}`);
            }
          }
          compared++;
        }
      }
      figures.push(`shared/robots: ${compared} (chain, convention) pairs compared with the CLI`);
      assert(bad.length === 0, `${bad.length} of ${compared} differ:\n${bad.slice(0, 10).join('\n')}`);
    });

    await test('the JS API\'s check JSON is the CLI\'s for every dh.yaml of ../shared/robots', async () => {
      let compared = 0;
      const bad = [];
      for (const d of fs.readdirSync(path.join(SHARED, 'robots')).sort()) {
        const dir = path.join(SHARED, 'robots', d);
        if (!fs.existsSync(path.join(dir, 'dh.yaml'))) continue;
        const want = cli(['check', 'robot.urdf', '--sheet', 'dh.yaml', '--format', 'json'], dir);
        const got = await page.evaluate(([u, s]) => {
          try {
            return { out: window.urdfDh.check(u, s, { sheet_name: 'dh.yaml' }) };
          } catch (e) {
            return { err: e.message };
          }
        }, [fs.readFileSync(path.join(dir, 'robot.urdf'), 'utf8'), fs.readFileSync(path.join(dir, 'dh.yaml'), 'utf8')]);
        if (want.code === 2) {
          const first = want.err.split('\n').find((l) => l.startsWith('urdf-dh: error: '));
          if (got.err === undefined || `urdf-dh: error: ${got.err.split('\n')[0]}` !== first) bad.push(`${d}: CLI ${first}, page ${got.err ?? 'no error'}`);
        } else {
          try {
            assertSameOutput(got.out, want.out, 'check json');
          } catch (e) {
            bad.push(`${d}: ${e.message}`);
          }
        }
        compared++;
      }
      figures.push(`shared/robots: ${compared} check reports compared with the CLI`);
      assert(compared > 0 && bad.length === 0, `${bad.length} of ${compared} differ:\n${bad.slice(0, 10).join('\n')}`);
    });
  } else {
    console.log(`skip  the JS API against the CLI on ../shared/robots: ${SHARED} is absent`);
  }

  const FORMATS = path.join(SHARED, 'formats');
  if (fs.existsSync(path.join(FORMATS, 'manifest.json'))) {
    await test('the JS API\'s JSON is the CLI\'s for the MJCF, SDFormat and xacro files of ../shared/formats', async () => {
      const models = JSON.parse(fs.readFileSync(path.join(FORMATS, 'manifest.json'), 'utf8')).models;
      // The text files below `dir` whose names end in one of `exts`, by path from FORMATS.
      const below = (dir, exts) => {
        const out = [];
        const walk = (d) => {
          for (const e of fs.readdirSync(d, { withFileTypes: true })) {
            const p = path.join(d, e.name);
            if (e.isDirectory()) walk(p);
            else if (exts.some((x) => e.name.endsWith(x))) out.push(path.relative(FORMATS, p));
          }
        };
        walk(dir);
        return out;
      };
      const counts = {};
      const bad = [];
      for (const m of models) {
        const file = path.join(FORMATS, m.file);
        const name = path.basename(file);
        const args = m.xacro_args || [];
        let given = [];
        let env;
        if (m.format === 'mjcf') given = below(path.dirname(file), ['.xml']);
        if (m.format === 'xacro') {
          given = m.ros_package_path.flatMap((d) => below(path.join(FORMATS, d), ['.xacro', '.urdf', '.yaml', '.yml', '.xml']));
          env = { ROS_PACKAGE_PATH: m.ros_package_path.map((d) => path.join(FORMATS, d)).join(':') };
        }
        const files = {};
        for (const g of given) if (g !== m.file) files[`/${g}`] = fs.readFileSync(path.join(FORMATS, g), 'utf8');
        const want = cli(['extract', name, '--base', m.base, '--tip', m.tip, '--format', 'json', ...args.flatMap((a) => ['--xacro-arg', a])], path.dirname(file), env);
        const got = await page.evaluate(([t, o]) => {
          try {
            return { out: window.urdfDh.extract(t, o) };
          } catch (e) {
            return { err: e.message };
          }
        }, [fs.readFileSync(file, 'utf8'), { name, path: `/${m.file}`, files, xacro_args: args, base: m.base, tip: m.tip, format: 'json' }]);
        if (want.code === 2) {
          const first = want.err.split('\n').find((l) => l.startsWith('urdf-dh: error: '));
          if (got.err === undefined || `urdf-dh: error: ${got.err.split('\n')[0]}` !== first) bad.push(`${m.id}: CLI ${first}, page ${got.err ?? 'no error'}`);
        } else if (got.err !== undefined) {
          bad.push(`${m.id}: CLI exit ${want.code}, page error ${got.err}`);
        } else {
          try {
            assertSameOutput(got.out, want.out, 'json');
          } catch (e) {
            bad.push(`${m.id}: ${e.message}`);
          }
        }
        counts[m.format] = (counts[m.format] || 0) + 1;
      }
      figures.push(`shared/formats: ${Object.entries(counts).map(([f, n]) => `${n} ${f}`).join(', ')} chains compared with the CLI`);
      assert(counts.mjcf > 0 && counts.sdf > 0 && counts.xacro > 0 && bad.length === 0, `${bad.length} differ:\n${bad.slice(0, 10).join('\n')}`);
    });
  } else {
    console.log(`skip  the JS API against the CLI on ../shared/formats (MJCF, SDFormat, xacro): ${FORMATS} is absent`);
  }

  await test('no console errors', async () => {
    assert(consoleErrors.length === 0, consoleErrors.join('\n'));
  });

  await test('no request left localhost', async () => {
    assert(outside.length === 0, outside.join('\n'));
  });

  await context.close();
  server.close();
  fs.rmSync(profile, { recursive: true, force: true });
  const wasm = fs.readFileSync(path.join(DIST, 'urdf_dh.wasm'));
  const { gzipSync } = await import('node:zlib');
  figures.push(`wasm: ${wasm.length} bytes, ${gzipSync(wasm, { level: 9 }).length} bytes gzipped; app.js ${fs.statSync(path.join(DIST, 'app.js')).size} bytes, ${gzipSync(fs.readFileSync(path.join(DIST, 'app.js')), { level: 9 }).length} gzipped`);
  figures.push(`outputs compared with the CLI: ${sameness.exact} byte for byte, ${sameness.noise} equal but for the last digits of numbers (libm)`);
  finish(figures.map((f) => `figure: ${f}`));
}

run(main);
