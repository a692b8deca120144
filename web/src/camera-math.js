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
