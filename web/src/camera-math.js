// The renderer's camera convention (renderer/src/core/scene_math.cpp, renderer/include/brdfa/scene.h):
// yaw in degrees about +Y, 0 looks down -Z; pitch in degrees, positive looks up, clamped to
// -89..89 by the server; fov is the vertical field of view in degrees. Pure functions only: the
// camera panel keeps the scene's camera JSON ({position, yaw, pitch, fov}) and these turn a
// drag, a wheel step or a button into the next one.
const rad = (d) => (d * Math.PI) / 180;

export const MAX_PITCH = 89;
export const clamp = (x, lo, hi) => Math.min(hi, Math.max(lo, x));

/** forward = (-sin(yaw) cos(pitch), sin(pitch), -cos(yaw) cos(pitch)); right = forward x +Y. */
export function basis(yaw, pitch) {
  const y = rad(yaw), p = rad(pitch);
  const forward = [-Math.sin(y) * Math.cos(p), Math.sin(p), -Math.cos(y) * Math.cos(p)];
  const right = [Math.cos(y), 0, -Math.sin(y)];
  return { forward, right, up: [0, 1, 0] };
}

/** Moves `position` by `amount` along the W/A/S/D/Q/E keys held (a Set of lower-case keys). */
export function move(position, yaw, pitch, keys, amount) {
  const { forward, right, up } = basis(yaw, pitch);
  const axes = { w: [forward, 1], s: [forward, -1], d: [right, 1], a: [right, -1], q: [up, 1], e: [up, -1] };
  const p = position.slice();
  for (const k of keys) {
    const axis = axes[k];
    if (!axis) continue;
    for (let i = 0; i < 3; ++i) p[i] += axis[0][i] * axis[1] * amount;
  }
  return p;
}

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];

/**
 * How far the camera must back off along its view axis (>= 0) so that every sphere
 * {center, radius} lies inside the view frustum (vertical field of view `fov` degrees, width /
 * height `aspect`). For each side plane through the eye at half-angle h, a sphere at lateral
 * offset u and depth z is inside when z sin h - |u| cos h >= radius.
 */
export function backOffToFit(camera, spheres, aspect = 1) {
  const { forward, right } = basis(camera.yaw, camera.pitch);
  const up = cross(right, forward);
  const halfV = rad(camera.fov) / 2;
  const halfH = Math.atan(Math.tan(halfV) * aspect);
  let back = 0;
  for (const { center, radius } of spheres) {
    const rel = [0, 1, 2].map((i) => center[i] - camera.position[i]);
    const z = dot(rel, forward);
    const need = Math.max((radius + Math.abs(dot(rel, up)) * Math.cos(halfV)) / Math.sin(halfV),
      (radius + Math.abs(dot(rel, right)) * Math.cos(halfH)) / Math.sin(halfH));
    back = Math.max(back, need - z);
  }
  return back;
}

/** `position` moved `distance` against the view direction. */
export function backOff(position, yaw, pitch, distance) {
  const { forward } = basis(yaw, pitch);
  return position.map((p, i) => p - forward[i] * distance);
}

/** The camera position moved across its view axis (not along it) so the axis passes through
 *  the mean of `points`. */
export function centreOn(camera, points) {
  const { forward } = basis(camera.yaw, camera.pitch);
  const mean = [0, 1, 2].map((i) => points.reduce((a, p) => a + p[i], 0) / points.length);
  const rel = mean.map((m, i) => m - camera.position[i]);
  const along = dot(rel, forward);
  return camera.position.map((p, i) => p + rel[i] - forward[i] * along);
}

const sub = (a, b) => a.map((v, i) => v - b[i]);
const length = (a) => Math.hypot(a[0], a[1], a[2]);

/** `v` turned by `angle` degrees about the unit `axis` (Rodrigues' formula, right-handed). */
export function rotate(v, axis, angle) {
  const c = Math.cos(rad(angle)), s = Math.sin(rad(angle));
  const kxv = cross(axis, v), kv = dot(axis, v);
  return v.map((x, i) => x * c + kxv[i] * s + axis[i] * kv * (1 - c));
}

/** Degrees folded into (-180, 180]. */
export const wrapDegrees = (d) => { const w = ((d % 360) + 360) % 360; return w > 180 ? w - 360 : w; };

/**
 * Orbit: the camera turned as one rigid piece about `pivot`, first `dYaw` degrees about the
 * vertical through the pivot, then `dPitch` about the horizontal line through it parallel to the
 * camera's right axis. A turn of the whole rig by an angle about +Y adds that angle to yaw, and
 * one about the right axis adds it to pitch (forward = cos(pitch) h + sin(pitch) Y turns within
 * the plane of h and Y), so the camera keeps looking at the pivot the way it did: its distance
 * to the pivot and where the pivot appears in the image do not change. Pitch stays within
 * +-MAX_PITCH (the turn is cut short there, so the rig stays rigid).
 */
export function orbit(camera, pivot, dYaw, dPitch) {
  const pitch = clamp(camera.pitch + dPitch, -MAX_PITCH, MAX_PITCH);
  const yaw = camera.yaw + dYaw;
  let offset = rotate(sub(camera.position, pivot), [0, 1, 0], dYaw);
  offset = rotate(offset, basis(yaw, 0).right, pitch - camera.pitch);
  return { ...camera, position: pivot.map((p, i) => p + offset[i]), yaw: wrapDegrees(yaw), pitch };
}

/** Tightest half-angle of the view, radians: the vertical one, or the horizontal one when the
 *  image is taller than wide (aspect = width / height). */
export function halfAngle(fov, aspect = 1) {
  const halfV = rad(fov) / 2;
  return Math.min(halfV, Math.atan(Math.tan(halfV) * aspect));
}

/** The frame keeps this much room around a framed object: its bounding sphere spans 1 / 1.15
 *  of the sine of the tightest half-angle. */
export const FRAME_MARGIN = 1.15;

/** Distance from a sphere's centre at which the sphere fits the view: a sphere of radius r seen
 *  from distance d spans a cone of half-angle asin(r / d), so d = margin r / sin(half-angle). */
export const fitDistance = (radius, fov, aspect = 1, margin = FRAME_MARGIN) =>
  (margin * radius) / Math.sin(halfAngle(fov, aspect));

/** "Frame object": the camera, keeping its direction, moved to look at the sphere's centre from
 *  fitDistance. */
export function frameSphere(camera, { center, radius }, aspect = 1) {
  const { forward } = basis(camera.yaw, camera.pitch);
  const d = fitDistance(radius, camera.fov, aspect);
  return { ...camera, position: center.map((c, i) => c - forward[i] * d) };
}

/** Orbit distances for a sphere: from just outside it to 20 fit distances (the object then
 *  spans a twentieth of the frame), and never past 900, inside the renderer's far plane (1000). */
export const orbitLimits = ({ radius }, fov, aspect = 1) =>
  ({ min: 1.1 * radius, max: Math.min(900, 20 * fitDistance(radius, fov, aspect)) });

/** The camera moved along the line to `pivot` so its distance is multiplied by `factor`, kept
 *  within [min, max] (a camera already outside the range is never moved further out of it).
 *  The direction from the camera to the pivot is kept, so the pivot stays where it appears. */
export function dolly(camera, pivot, factor, { min, max }) {
  const offset = sub(camera.position, pivot);
  const d = length(offset);
  if (!(d > 0)) return camera;
  const next = clamp(d * factor, Math.min(min, d), Math.max(max, d));
  return { ...camera, position: pivot.map((p, i) => p + (offset[i] * next) / d) };
}
