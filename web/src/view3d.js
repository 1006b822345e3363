// The 3-D view: draws what the library computed (crates/wasm's Robot.fk), nothing more: the
// URDF's links and frames, the joint axes, the DH frames (x and z) and the common normals, in
// the base link frame with z up. Poses arrive as column-major 4x4 matrices.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

const COLORS = {
  link: 0x8a94a6,
  joint: 0x5b6578,
  axis: 0xf59e0b,
  dx: 0xef4444,
  dz: 0x3b82f6,
  normal: 0xd946ef,
  highlight: 0xfde047,
  diff: 0xff2d55,
};

const Y = new THREE.Vector3(0, 1, 0);

// A cylinder from `a` to `b` (a unit cylinder along y, placed and stretched).
function placeRod(mesh, a, b) {
  const dir = new THREE.Vector3().subVectors(b, a);
  const len = dir.length();
  mesh.visible = len > 1e-9;
  if (!mesh.visible) return;
  mesh.position.copy(a).addScaledVector(dir, 0.5);
  mesh.quaternion.setFromUnitVectors(Y, dir.divideScalar(len));
  mesh.scale.set(1, len, 1);
}

function origin(m) {
  return new THREE.Vector3(m[12], m[13], m[14]);
}

export class View3D {
  constructor(el) {
    this.el = el;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    el.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x0f172a);
    this.camera = new THREE.PerspectiveCamera(40, 1, 0.001, 100);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(1.6, -1.6, 1.2);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.render());
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x334155, 2.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(2, -3, 4);
    this.scene.add(sun);
    this.grid = new THREE.GridHelper(2, 20, 0x334155, 0x1e293b);
    this.grid.rotation.x = Math.PI / 2;
    this.scene.add(this.grid);
    this.group = new THREE.Group();
    this.scene.add(this.group);
    this.selected = -1;
    this.diffs = [];
    new ResizeObserver(() => this.resize()).observe(el);
    this.resize();
  }

  resize() {
    const w = this.el.clientWidth || 600;
    const h = this.el.clientHeight || 400;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  render() {
    this.renderer.render(this.scene, this.camera);
  }

  clear() {
    this.group.clear();
    this.items = null;
    this.render();
  }

  // Builds the objects of a chain of `joints` and places them at `scene` (zero pose).
  setRobot(joints, scene) {
    this.group.clear();
    this.selected = -1;
    this.diffs = [];
    let size = 0.2;
    for (const m of [...scene.urdf, ...scene.dh]) size = Math.max(size, origin(m).length());
    this.size = size;
    const r = size * 0.012;
    const mat = (color, extra = {}) => new THREE.MeshStandardMaterial({ color, roughness: 0.55, metalness: 0.1, ...extra });
    const rod = (radius, material) => new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, 1, 16), material);
    const n = joints.length;
    const items = { links: [], joints: [], axes: [], urdfFrames: [], dh: [], normals: [] };
    for (let i = 0; i <= n; i++) {
      const link = rod(r, mat(COLORS.link));
      items.links.push(link);
      this.group.add(link);
      const ball = new THREE.Mesh(new THREE.SphereGeometry(r * 1.8, 20, 12), mat(COLORS.joint));
      items.joints.push(ball);
      this.group.add(ball);
      const triad = new THREE.AxesHelper(size * 0.07);
      triad.matrixAutoUpdate = false;
      items.urdfFrames.push(triad);
      this.group.add(triad);
    }
    for (let i = 0; i < n; i++) {
      const axis = rod(r * 0.45, mat(COLORS.axis, { emissive: COLORS.axis, emissiveIntensity: 0.25 }));
      items.axes.push(axis);
      this.group.add(axis);
      const geo = new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]);
      const normal = new THREE.Line(geo, new THREE.LineDashedMaterial({ color: COLORS.normal, dashSize: size * 0.02, gapSize: size * 0.012 }));
      items.normals.push(normal);
      this.group.add(normal);
    }
    for (let i = 0; i <= n; i++) {
      const frame = new THREE.Group();
      frame.matrixAutoUpdate = false;
      const len = size * 0.14;
      frame.add(new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), len, COLORS.dx, len * 0.22, len * 0.12));
      frame.add(new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), len, COLORS.dz, len * 0.22, len * 0.12));
      const dot = new THREE.Mesh(new THREE.SphereGeometry(r * 1.2, 12, 8), new THREE.MeshBasicMaterial({ color: 0xffffff }));
      frame.add(dot);
      items.dh.push(frame);
      this.group.add(frame);
    }
    this.items = items;
    this.grid.scale.setScalar(Math.max(0.5, size));
    // Frame the zero pose: its bounding sphere fills the view, seen from the front right.
    const box = new THREE.Box3().setFromPoints([new THREE.Vector3(), ...scene.urdf.map(origin), ...scene.dh.map(origin)]);
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    const radius = (Math.max(sphere.radius, 0.1) + size * 0.16) * 1.1;
    const fov = THREE.MathUtils.degToRad(this.camera.fov);
    const dist = radius / Math.sin(Math.min(fov, fov * this.camera.aspect) / 2);
    const dir = new THREE.Vector3(1, -1.3, 0.75).normalize();
    this.camera.position.copy(sphere.center).addScaledVector(dir, dist);
    this.controls.target.copy(sphere.center);
    this.camera.near = size * 0.005;
    this.camera.far = size * 50;
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.update(scene);
  }

  // Places every object at `scene` (the library's FK at the sliders' joint values).
  update(scene) {
    const it = this.items;
    if (!it) return;
    const n = it.axes.length;
    let prev = new THREE.Vector3();
    for (let i = 0; i <= n; i++) {
      const m = scene.urdf[i];
      const p = origin(m);
      placeRod(it.links[i], prev, p);
      it.joints[i].position.copy(p);
      it.urdfFrames[i].matrix.fromArray(m);
      prev = p;
    }
    const half = this.size * 0.16;
    for (let i = 0; i < n; i++) {
      // Centred on the joint frame's origin (the child link frame's, which lies on the axis),
      // not on the axis line's point nearest the base origin.
      const [, , , dx, dy, dz] = scene.axes[i];
      const p = origin(scene.urdf[i]);
      const d = new THREE.Vector3(dx, dy, dz);
      placeRod(it.axes[i], p.clone().addScaledVector(d, -half), p.clone().addScaledVector(d, half));
      const [ax, ay, az, bx, by, bz] = scene.normals[i];
      it.normals[i].geometry.setFromPoints([new THREE.Vector3(ax, ay, az), new THREE.Vector3(bx, by, bz)]);
      it.normals[i].computeLineDistances();
    }
    for (let i = 0; i <= n; i++) it.dh[i].matrix.fromArray(scene.dh[i]);
    this.paint();
  }

  // Row `i` (0-based; -1 for none): its joint axis and its DH frame (frame i + 1) in yellow.
  highlight(i) {
    this.selected = i;
    this.paint();
  }

  // Joints (row indices) that a check found different: their axes in red.
  markDifferences(rows) {
    this.diffs = rows;
    this.paint();
  }

  paint() {
    const it = this.items;
    if (!it) return this.render();
    it.axes.forEach((a, i) => {
      const c = i === this.selected ? COLORS.highlight : this.diffs.includes(i) ? COLORS.diff : COLORS.axis;
      a.material.color.setHex(c);
      a.material.emissive.setHex(c);
      a.scale.x = a.scale.z = i === this.selected || this.diffs.includes(i) ? 2.2 : 1;
    });
    it.dh.forEach((f, k) => {
      const on = this.selected >= 0 && k === this.selected + 1;
      f.children[2].material.color.setHex(on ? COLORS.highlight : 0xffffff);
      f.children[2].scale.setScalar(on ? 2.5 : 1);
    });
    this.render();
  }
}
