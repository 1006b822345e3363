// The urdf-dh page: every number comes from the library compiled to WebAssembly (crates/wasm),
// which returns the CLI's own texts; this script only reads files, fills the page and draws.
import init, * as wasm from '../build/pkg/urdf_dh_wasm.js';
import { View3D } from './view3d.js';

const $ = (id) => document.getElementById(id);

const state = {
  text: null, // the robot file's text
  name: 'robot.urdf', // its file name, as the CLI shows it in messages
  path: null, // its path among `files` (a dropped folder keeps its layout)
  files: {}, // every file given, by path: xacro includes, packages, YAML, MJCF includes
  sheet: null, // the extracted sheet (parsed JSON of `extract --format json`)
  robot: null, // wasm.Robot of the chosen chain (for the sliders)
  joints: [],
  q: [],
  selected: -1,
  gallerySheet: null,
};

const ready = init({ module_or_path: new URL('urdf_dh.wasm', import.meta.url) });

// The API for scripts and tests: the CLI's texts, byte for byte.
window.urdfDh = {
  ready,
  extract: (text, options = {}) => wasm.extract(text, JSON.stringify(options)),
  check: (urdfText, sheetText, options = {}) =>
    wasm.check(urdfText, sheetText, JSON.stringify(options)),
  toUrdf: (sheetText, options = {}) => wasm.to_urdf(sheetText, JSON.stringify(options)),
  // `options`: a file name (string) or {name, path, files, xacro_args, packages}.
  tree: (text, options = 'robot.urdf') =>
    JSON.parse(wasm.tree(text, JSON.stringify(typeof options === 'string' ? { name: options } : options))),
  // Both forward kinematics of a chain at joint values q: {urdf, axes, dh, normals, dh_tip},
  // poses as column-major 4x4 matrices in the base link frame (metres).
  fk: (text, options, q) => {
    const robot = new wasm.Robot(text, JSON.stringify(options || {}));
    try {
      return JSON.parse(robot.fk(new Float64Array(q)));
    } finally {
      robot.free();
    }
  },
  // The warnings `extract` prints on stderr, without `urdf-dh: warning: `.
  warnings: (text, options = {}) => JSON.parse(wasm.extract_warnings(text, JSON.stringify(options))),
  // One extraction to read several times: .output(format) (the CLI's text, proved as written),
  // .warnings() (JSON), .joints() (JSON), .fk(Float64Array); free it with .free().
  robot: (text, options = {}) => new wasm.Robot(text, JSON.stringify(options)),
  lastTiming: null,
  loads: 0, // robot files read so far (a test waits for the next)
  load: (text, name) => loadFiles([{ path: `/${name}`, text }]),
  // Several files (a folder), each {path, text}: the robot file is chosen as a drop chooses it.
  loadFiles: (files) => loadFiles(files),
};

let view = null;

// How the robot file is read: its name and path, the files beside it, the xacro arguments.
function source() {
  const files = {};
  for (const [p, t] of Object.entries(state.files)) if (p !== state.path) files[p] = t;
  const args = $('xacro-args').value.trim();
  return {
    name: state.name,
    path: state.path || undefined,
    files,
    xacro_args: args ? args.split(/\s+/) : [],
  };
}

function options() {
  return {
    ...source(),
    base: $('base').value || undefined,
    tip: $('tip').value || undefined,
    convention: $('convention').value,
    length_unit: $('length-unit').value,
    angle_unit: $('angle-unit').value,
  };
}

function showError(message) {
  const el = $('error');
  el.textContent = message ? `error: ${message}` : '';
  el.hidden = !message;
}

function errorText(e) {
  return e instanceof Error ? e.message : String(e);
}

// The link tree as select options, depth-first from the root, indented by depth.
function fillChainSelects(tree) {
  const children = new Map();
  for (const l of tree.links) {
    if (l.parent !== null) {
      if (!children.has(l.parent)) children.set(l.parent, []);
      children.get(l.parent).push(l.name);
    }
  }
  const order = [];
  const walk = (name, depth) => {
    order.push([name, depth]);
    for (const c of children.get(name) || []) walk(c, depth + 1);
  };
  walk(tree.root, 0);
  for (const id of ['base', 'tip']) {
    const sel = $(id);
    sel.replaceChildren();
    for (const [name, depth] of order) {
      const opt = document.createElement('option');
      opt.value = name;
      opt.textContent = `${'\u00a0'.repeat(Math.min(depth, 8))}${name}`;
      sel.appendChild(opt);
    }
  }
  if (tree.default) {
    $('base').value = tree.default.base;
    $('tip').value = tree.default.tip;
  }
}

// The robot files among `files` ({path: text}), most likely first: a file no other file
// includes, then by kind (a top-level xacro, a URDF, a xacro, SDFormat, MJCF), then the
// shallowest, then by name. Which format a file holds is told as the CLI tells it: a `.xacro`
// name is expanded, then the content decides (<mujoco>, <sdf>, else URDF).
function robotCandidates(files) {
  const paths = Object.keys(files);
  const base = (p) => p.slice(p.lastIndexOf('/') + 1);
  const rank = (p) => {
    const n = base(p).toLowerCase();
    if (n.endsWith('.urdf.xacro')) return 0;
    if (n.endsWith('.urdf')) return 1;
    if (n.endsWith('.xacro')) return 2;
    if (n.endsWith('.sdf') || n.endsWith('.world')) return 3;
    if (n.endsWith('.xml') && n !== 'package.xml' && /<mujoco[\s>]/.test(files[p])) return 4;
    if (paths.length === 1) return 5;
    return -1;
  };
  // Named in an include (xacro's filename="...", MJCF's file="...") of another file.
  const included = (p) => {
    const n = base(p);
    return paths.some((q) => q !== p && (files[q].includes(`/${n}"`) || files[q].includes(`="${n}"`)));
  };
  const depth = (p) => p.split('/').length;
  return paths
    .filter((p) => rank(p) >= 0)
    .map((p) => [p, included(p) ? 1 : 0, rank(p), depth(p)])
    .sort((a, b) => a[1] - b[1] || a[2] - b[2] || a[3] - b[3] || (a[0] < b[0] ? -1 : 1))
    .map((c) => c[0]);
}

// Reads the given files ([{path, text}]) and shows the most likely robot file among them.
async function loadFiles(list, galleryButton = null, xacroArgs = '') {
  state.files = {};
  for (const f of list) state.files[f.path] = f.text;
  const candidates = robotCandidates(state.files);
  const sel = $('robot-file');
  sel.replaceChildren();
  for (const p of candidates) {
    const opt = document.createElement('option');
    opt.value = p;
    opt.textContent = p.replace(/^\//, '');
    sel.appendChild(opt);
  }
  $('robot-file-row').hidden = candidates.length < 2;
  $('xacro-args').value = xacroArgs;
  if (candidates.length === 0) {
    clearResults();
    showError(`no robot file among the ${list.length} file(s) given (expected .urdf, .xacro, .sdf, .world, or an MJCF .xml)`);
    return;
  }
  await loadRobot(candidates[0], galleryButton);
}

// Reads the robot file at `path` of the files given; counts the loads (for tests).
async function loadRobot(path, galleryButton = null) {
  try {
    await readRobot(path, galleryButton);
  } finally {
    window.urdfDh.loads += 1;
  }
}

async function readRobot(path, galleryButton) {
  await ready;
  for (const b of $('gallery').children) b.classList.toggle('active', b === galleryButton);
  if (!galleryButton) {
    state.gallerySheet = null;
    $('gallery-sheet').hidden = true;
  }
  const t0 = performance.now();
  state.path = path;
  state.text = state.files[path];
  state.name = path.slice(path.lastIndexOf('/') + 1);
  $('robot-file').value = path;
  const others = Object.keys(state.files).length - 1;
  $('file-name').textContent = others > 0 ? `${state.name} (and ${others} file(s) beside it)` : state.name;
  $('xacro-row').hidden = !state.name.endsWith('.xacro');
  $('check-result').replaceChildren();
  let tree;
  try {
    tree = JSON.parse(wasm.tree(state.text, JSON.stringify(source())));
  } catch (e) {
    clearResults();
    showError(errorText(e));
    return;
  }
  fillChainSelects(tree);
  $('format').textContent = tree.format;
  if (!tree.default) {
    clearResults();
    showError(tree.default_error);
    return;
  }
  run(t0);
}

function clearResults() {
  state.sheet = null;
  if (state.robot) state.robot.free();
  state.robot = null;
  $('dh-table').tHead.replaceChildren();
  $('dh-table').tBodies[0].replaceChildren();
  $('pairs').tBodies[0].replaceChildren();
  $('warnings').replaceChildren();
  $('verdict').textContent = '';
  $('verdict').className = 'verdict';
  $('title').textContent = '';
  $('frames').textContent = '';
  $('sliders').replaceChildren();
  if (view) view.clear();
}

// Extracts the chosen chain once (a wasm.Robot), proves its JSON and text as written (the
// robot file's side of the proof computed once for both), fills the page; `t0` times the whole.
function run(t0 = performance.now()) {
  showError('');
  const o = options();
  let json;
  let text;
  let warnings;
  try {
    if (state.robot) state.robot.free();
    state.robot = null;
    state.robot = new wasm.Robot(state.text, JSON.stringify(o));
    json = state.robot.output('json');
    text = state.robot.output('text');
    warnings = JSON.parse(state.robot.warnings());
  } catch (e) {
    clearResults();
    showError(errorText(e));
    return;
  }
  state.sheet = JSON.parse(json);
  state.joints = JSON.parse(state.robot.joints());
  state.q = state.joints.map(() => 0);
  state.selected = -1;
  const lines = text.trimEnd().split('\n');
  renderTable(state.sheet, lines[0]);
  renderVerdict(lines[lines.length - 1]);
  renderPairs(state.sheet);
  renderWarnings(warnings);
  renderSliders();
  if (view) view.setRobot(state.joints, JSON.parse(state.robot.fk(new Float64Array(state.q))));
  updateTipGap();
  const ms = performance.now() - t0;
  window.urdfDh.lastTiming = ms;
  $('timing').textContent = `extracted once, proved as written twice (JSON and text) and drawn in ${ms.toFixed(1)} ms`;
}

const fmt = (v) => (v === null || v === undefined ? '' : Number(v).toFixed(6));

function renderTable(sheet, title) {
  $('title').textContent = title;
  const L = sheet.length_unit;
  const A = sheet.angle_unit;
  const head = document.createElement('tr');
  for (const h of ['#', 'joint', 'type', `theta [${A}]`, `d [${L}]`, `a [${L}]`, `alpha [${A}]`, `lower [${A}]`, `upper [${A}]`]) {
    const th = document.createElement('th');
    th.textContent = h;
    head.appendChild(th);
  }
  $('dh-table').tHead.replaceChildren(head);
  const body = $('dh-table').tBodies[0];
  body.replaceChildren();
  sheet.joints.forEach((j, i) => {
    const tr = document.createElement('tr');
    tr.dataset.joint = j.name;
    tr.dataset.index = String(i);
    // Limits in the header's angle unit; a prismatic joint's in the length unit, said so.
    const unit = j.type === 'prismatic' ? ` ${L}` : '';
    const cells = [
      ['index', String(i + 1)],
      ['name', j.name],
      ['type', j.type],
      ['theta', fmt(j.theta)],
      ['d', fmt(j.d)],
      ['a', fmt(j.a)],
      ['alpha', fmt(j.alpha)],
      ['lower', j.lower === undefined ? '' : `${fmt(j.lower)}${unit}`],
      ['upper', j.upper === undefined ? '' : `${fmt(j.upper)}${unit}`],
    ];
    for (const [param, value] of cells) {
      const td = document.createElement('td');
      td.dataset.param = param;
      td.textContent = value;
      tr.appendChild(td);
    }
    tr.addEventListener('click', () => select(i));
    body.appendChild(tr);
  });
  const pose = (p, u) => `xyz [${L}] ${p.xyz.map(fmt).join(' ')}  rpy [${A}] ${p.rpy.map(fmt).join(' ')}`;
  $('frames').textContent =
    `base: DH frame 0 in ${sheet.base_link}: ${pose(sheet.base)}\n` +
    `tool: ${sheet.tip_link} in DH frame ${sheet.joints.length}: ${pose(sheet.tool)}`;
}

function renderVerdict(line) {
  const el = $('verdict');
  el.textContent = line;
  el.className = `verdict ${/: PASS$/.test(line) ? 'pass' : 'fail'}`;
}

function renderPairs(sheet) {
  const body = $('pairs').tBodies[0];
  body.replaceChildren();
  for (const p of sheet.pairs || []) {
    const tr = document.createElement('tr');
    for (const v of [
      `${p.joints[0]} \u2192 ${p.joints[1]}`,
      p.relation,
      `${fmt(p.angle)} ${sheet.angle_unit}`,
      `${fmt(p.distance)} ${sheet.length_unit}`,
    ]) {
      const td = document.createElement('td');
      td.textContent = v;
      tr.appendChild(td);
    }
    body.appendChild(tr);
  }
}

function renderWarnings(warnings) {
  const ul = $('warnings');
  ul.replaceChildren();
  if (warnings.length === 0) {
    const li = document.createElement('li');
    li.className = 'none';
    li.textContent = 'none';
    ul.appendChild(li);
  }
  for (const w of warnings) {
    const li = document.createElement('li');
    li.textContent = w;
    ul.appendChild(li);
  }
}

function renderSliders() {
  const box = $('sliders');
  box.replaceChildren();
  state.joints.forEach((j, i) => {
    const row = document.createElement('label');
    row.className = 'slider';
    const name = document.createElement('span');
    name.className = 'joint-name';
    name.textContent = j.name;
    const input = document.createElement('input');
    input.type = 'range';
    input.dataset.testid = `slider-${i}`;
    input.setAttribute('data-testid', `slider-${i}`);
    const span = j.kind === 'prismatic' ? 0.5 : Math.PI;
    input.min = String(j.lower ?? -span);
    input.max = String(j.upper ?? span);
    input.step = 'any';
    const start = Math.min(Math.max(0, Number(input.min)), Number(input.max));
    input.value = String(start);
    state.q[i] = start;
    const value = document.createElement('span');
    value.className = 'joint-value';
    const show = () => {
      value.textContent = j.kind === 'prismatic' ? `${state.q[i].toFixed(3)} m` : `${((state.q[i] * 180) / Math.PI).toFixed(1)}\u00b0`;
    };
    show();
    input.addEventListener('input', () => {
      state.q[i] = Number(input.value);
      show();
      moved();
    });
    input.addEventListener('focus', () => select(i));
    row.append(name, input, value);
    box.appendChild(row);
  });
}

function moved() {
  if (!state.robot) return;
  if (view) view.update(JSON.parse(state.robot.fk(new Float64Array(state.q))));
  updateTipGap();
}

// How far the DH table's tip is from the URDF's at the sliders' joint values.
function updateTipGap() {
  if (!state.robot) return;
  const s = JSON.parse(state.robot.fk(new Float64Array(state.q)));
  const u = s.urdf[s.urdf.length - 1];
  const d = s.dh_tip;
  const gap = Math.hypot(u[12] - d[12], u[13] - d[13], u[14] - d[14]);
  $('tip-gap').textContent = `tip: URDF vs DH ${gap.toExponential(1)} m apart`;
}

function select(i) {
  state.selected = state.selected === i ? -1 : i;
  for (const tr of $('dh-table').tBodies[0].rows) {
    tr.classList.toggle('selected', Number(tr.dataset.index) === state.selected);
  }
  if (view) view.highlight(state.selected);
}

function download(name, text, type) {
  const url = URL.createObjectURL(new Blob([text], { type }));
  const a = document.createElement('a');
  a.href = url;
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

const EXT = { yaml: 'yaml', json: 'json', csv: 'csv', markdown: 'md' };

function onDownload(format) {
  if (!state.sheet || !state.robot) return;
  const stem = (state.sheet.robot || state.name.replace(/\.[^.]*$/, '') || 'robot').replace(/[^\w.-]+/g, '_');
  try {
    if (format === 'urdf') {
      const yaml = state.robot.output('yaml');
      const sheetName = `${stem}.dh.yaml`;
      download(`${stem}.dh.urdf`, wasm.to_urdf(yaml, JSON.stringify({ sheet_name: sheetName })), 'application/xml');
    } else {
      const text = state.robot.output(format);
      download(`${stem}.dh.${EXT[format]}`, text, 'text/plain');
    }
  } catch (e) {
    showError(errorText(e));
  }
}

function runCheck(sheetText, sheetName) {
  const box = $('check-result');
  box.replaceChildren();
  for (const td of document.querySelectorAll('#dh-table td.diff, #dh-table tr.diff')) td.classList.remove('diff');
  if (!state.text) return;
  const o = { ...source(), sheet_name: sheetName, base: $('base').value, tip: $('tip').value };
  let report;
  let warnings;
  try {
    report = JSON.parse(wasm.check(state.text, sheetText, JSON.stringify(o)));
    warnings = JSON.parse(wasm.check_warnings(state.text, sheetText, JSON.stringify(o)));
  } catch (e) {
    box.className = 'check-result fail';
    box.textContent = `error: ${errorText(e)}`;
    return;
  }
  const head = document.createElement('div');
  head.className = 'check-head';
  head.dataset.testid = 'check-verdict';
  head.setAttribute('data-testid', 'check-verdict');
  head.textContent = report.matches
    ? `MATCH: ${sheetName} and the URDF describe the same kinematics`
    : `MISMATCH: ${report.differences.length} difference(s) with ${sheetName}`;
  box.className = `check-result ${report.matches ? 'pass' : 'fail'}`;
  box.appendChild(head);
  const joints = [];
  for (const d of report.differences) {
    const li = document.createElement('div');
    li.className = 'difference';
    li.textContent = `${d.joint ?? '-'}  ${d.parameter}: URDF ${d.urdf.toPrecision(6)}, sheet ${d.sheet.toPrecision(6)} (${d.note})`;
    box.appendChild(li);
    if (d.joint) {
      const tr = [...$('dh-table').tBodies[0].rows].find((r) => r.dataset.joint === d.joint);
      if (tr) {
        const td = tr.querySelector(`td[data-param="${d.parameter}"]`);
        (td || tr).classList.add('diff');
        joints.push(Number(tr.dataset.index));
      }
    }
  }
  if (report.max_position_error !== null) {
    const lit = document.createElement('div');
    lit.className = 'literal';
    lit.textContent = `sheet taken literally, ${report.samples} samples: max position error ${report.max_position_error.toExponential(3)} m, max orientation error ${report.max_orientation_error.toExponential(3)} rad (bound ${report.position_bound.toExponential(1)} m, ${report.orientation_bound.toExponential(1)} rad)`;
    box.appendChild(lit);
  }
  for (const w of [...warnings, ...report.warnings]) {
    const div = document.createElement('div');
    div.className = 'warning';
    div.textContent = `warning: ${w}`;
    box.appendChild(div);
  }
  if (view) view.markDifferences(joints);
}

async function readFile(file) {
  return await file.text();
}

// The files of an <input type=file> (several files, or a folder with webkitdirectory), each
// {path, text}; a folder keeps its layout, so that includes and packages resolve.
async function readInput(fileList) {
  return Promise.all(
    [...fileList].map(async (f) => ({ path: `/${f.webkitRelativePath || f.name}`, text: await f.text() })),
  );
}

// The files of a drop: files and whole folders (walked through the entries API).
async function readDrop(dataTransfer) {
  const entries = [...dataTransfer.items].map((i) => (i.webkitGetAsEntry ? i.webkitGetAsEntry() : null));
  if (entries.some((e) => e === null)) return readInput(dataTransfer.files);
  const out = [];
  const walk = async (entry) => {
    if (entry.isFile) {
      const file = await new Promise((ok, fail) => entry.file(ok, fail));
      out.push({ path: entry.fullPath, text: await file.text() });
    } else if (entry.isDirectory) {
      const reader = entry.createReader();
      for (;;) {
        const batch = await new Promise((ok, fail) => reader.readEntries(ok, fail));
        if (batch.length === 0) break;
        for (const e of batch) await walk(e);
      }
    }
  };
  for (const e of entries) await walk(e);
  return out;
}

async function loadGallery() {
  const box = $('gallery');
  let list = [];
  try {
    list = await (await fetch('gallery.json')).json();
  } catch {
    return;
  }
  for (const item of list) {
    const b = document.createElement('button');
    b.textContent = item.name.replace(/_/g, ' ');
    b.setAttribute('data-testid', `gallery-${item.name}`);
    b.addEventListener('click', async () => {
      // Each file at its path below the gallery entry's folder, the robot file first.
      const files = await Promise.all(
        item.files.map(async (p) => ({ path: `/${p}`, text: await (await fetch(`${item.dir}/${p}`)).text() })),
      );
      await loadFiles(files, b, item.xacro_args || '');
      state.gallerySheet = item.sheet;
      $('gallery-sheet').hidden = !item.sheet;
    });
    box.appendChild(b);
  }
}

function wire() {
  for (const id of ['urdf-file', 'robot-folder']) {
    $(id).addEventListener('change', async (ev) => {
      if (ev.target.files.length === 0) return;
      await loadFiles(await readInput(ev.target.files));
    });
  }
  $('robot-file').addEventListener('change', () => loadRobot($('robot-file').value));
  $('xacro-args').addEventListener('change', () => state.path && loadRobot(state.path));
  const drop = $('drop');
  for (const t of ['dragenter', 'dragover']) {
    drop.addEventListener(t, (ev) => {
      ev.preventDefault();
      drop.classList.add('over');
    });
  }
  for (const t of ['dragleave', 'drop']) drop.addEventListener(t, () => drop.classList.remove('over'));
  drop.addEventListener('drop', async (ev) => {
    ev.preventDefault();
    const files = await readDrop(ev.dataTransfer);
    if (files.length > 0) await loadFiles(files);
  });
  for (const id of ['base', 'tip', 'convention', 'length-unit', 'angle-unit']) {
    $(id).addEventListener('change', () => state.text && run());
  }
  for (const b of document.querySelectorAll('.downloads button')) {
    b.addEventListener('click', () => onDownload(b.dataset.format));
  }
  $('sheet-file').addEventListener('change', async (ev) => {
    const f = ev.target.files[0];
    if (f) runCheck(await readFile(f), f.name);
  });
  $('gallery-sheet').addEventListener('click', async () => {
    if (!state.gallerySheet) return;
    runCheck(await (await fetch(state.gallerySheet)).text(), 'vendor.yaml');
  });
}

wire();
try {
  view = new View3D($('view3d'), { onPick: (i) => select(i) });
} catch (e) {
  showError(`the 3-D view cannot start (WebGL): ${errorText(e)}`);
}
await ready;
await loadGallery();
document.body.dataset.ready = 'true';
