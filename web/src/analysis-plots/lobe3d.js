// The 3D lobe (three.js, WebGL): f (luminance) over the hemisphere for one incident direction,
// each series a wire mesh in its colour over a faint surface, V times f / max f, so all series
// share one scale. The shading frame's N = +z is up; drag orbits, the wheel zooms. Rendered on
// demand (a new answer, a drag), never in a loop.
import {
  WebGLRenderer, Scene, PerspectiveCamera, Group, BufferGeometry, Float32BufferAttribute,
  LineSegments, LineBasicMaterial, LineDashedMaterial, Mesh, MeshBasicMaterial, DoubleSide, Color,
} from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { luminance } from '../analysis-series.js';
import { widthOf } from './canvas.js';

const HEIGHT = 215;
const MERIDIAN_EVERY = 10;   // azimuth steps between drawn meridians
const RING_EVERY = 5;        // polar steps between drawn rings
const rad = (d) => (d * Math.PI) / 180;

const lines = (points, material) => {
  const geo = new BufferGeometry();
  geo.setAttribute('position', new Float32BufferAttribute(points, 3));
  return new LineSegments(geo, material);
};

/** The surface's disk, the normal and the light's direction (scene furniture). */
function frame(thetaI) {
  const group = new Group();
  const disk = [];
  for (let k = 0; k < 64; ++k) {
    const a = (2 * Math.PI * k) / 64, b = (2 * Math.PI * (k + 1)) / 64;
    disk.push(Math.cos(a), Math.sin(a), 0, Math.cos(b), Math.sin(b), 0);
  }
  disk.push(-1, 0, 0, 1, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1.15);
  group.add(lines(disk, new LineBasicMaterial({ color: 0xbbbbbb })));
  // L at theta_i, azimuth 180 degrees (docs/api.md "Analysis": geometry).
  const L = [-Math.sin(rad(thetaI)), 0, Math.cos(rad(thetaI))].map((c) => 1.3 * c);
  const light = lines([...L, 0, 0, 0], new LineDashedMaterial({ color: 0x333333, dashSize: 0.06, gapSize: 0.04 }));
  light.computeLineDistances();
  group.add(light);
  return group;
}

/** One series: values[p][t] (azimuth p, polar angle t) as a wire mesh and a faint surface, both indexing one vertex array. */
function lobe(values, thetas, phis, scale, color) {
  const np = phis.length;
  const nt = thetas.length;
  const pos = new Float32Array(np * nt * 3);
  for (let p = 0; p < np; ++p) {
    const cp = Math.cos(rad(phis[p])), sp = Math.sin(rad(phis[p]));
    for (let t = 0; t < nt; ++t) {
      const r = (luminance(values[p][t]) || 0) * scale;
      const st = Math.sin(rad(thetas[t]));
      pos.set([r * st * cp, r * st * sp, r * Math.cos(rad(thetas[t]))], (p * nt + t) * 3);
    }
  }
  const at = (p, t) => (p % np) * nt + t;   // azimuths wrap around
  const wire = [];
  const tris = [];
  for (let p = 0; p < np; ++p) {
    for (let t = 0; t + 1 < nt; ++t) {
      if (p % MERIDIAN_EVERY === 0) wire.push(at(p, t), at(p, t + 1));
      tris.push(at(p, t), at(p + 1, t), at(p + 1, t + 1), at(p, t), at(p + 1, t + 1), at(p, t + 1));
    }
    for (let t = RING_EVERY; t < nt; t += RING_EVERY) wire.push(at(p, t), at(p + 1, t));
  }
  const vertices = new Float32BufferAttribute(pos, 3);
  const geometry = (index) => {
    const geo = new BufferGeometry();
    geo.setAttribute('position', vertices);
    geo.setIndex(index);
    return geo;
  };
  const group = new Group();
  group.add(new LineSegments(geometry(wire), new LineBasicMaterial({ color: new Color(color) })));
  group.add(new Mesh(geometry(tris), new MeshBasicMaterial({ color: new Color(color), transparent: true, opacity: 0.12, side: DoubleSide, depthWrite: false })));
  return group;
}

export function lobeView(host) {
  // preserveDrawingBuffer: the canvas keeps its pixels between renders (screenshots, copies).
  const renderer = new WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xffffff);
  renderer.setSize(widthOf(host), HEIGHT);
  host.replaceChildren(renderer.domElement);
  const scene = new Scene();
  const camera = new PerspectiveCamera(35, widthOf(host) / HEIGHT, 0.05, 50);
  camera.up.set(0, 0, 1);
  camera.position.set(0.9, -3.2, 1.6);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.set(0, 0, 0.35);
  controls.update();
  const render = () => renderer.render(scene, camera);
  controls.addEventListener('change', render);
  let content = new Group();
  scene.add(content);

  const dispose = (obj) => obj.traverse((o) => { o.geometry?.dispose(); o.material?.dispose(); });
  return {
    /** The lobe answer and the series' colours; returns the largest value (the scale's 1). */
    set(answer, colors) {
      scene.remove(content);
      dispose(content);
      content = new Group();
      const list = answer?.series || [];
      let top = 0;
      for (const s of list) for (const row of s.values) for (const v of row) top = Math.max(top, luminance(v) || 0);
      const scale = top > 0 ? 1 / top : 0;
      content.add(frame(answer?.theta_i ?? 0));
      list.forEach((s, i) => content.add(lobe(s.values, answer.axes.theta_deg, answer.axes.phi_deg, scale, colors[i])));
      scene.add(content);
      host.dataset.series = String(list.length);
      render();
      return top;
    },
    resize() {
      renderer.setSize(widthOf(host), HEIGHT);
      camera.aspect = widthOf(host) / HEIGHT;
      camera.updateProjectionMatrix();
      render();
    },
  };
}
