// The renderer's camera convention (renderer/src/scene_math.cpp): yaw in degrees about +Y, 0
// looks down -Z; pitch in degrees, clamped to -89..89 by the server.
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
