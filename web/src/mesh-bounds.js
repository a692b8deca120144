// Bounding spheres of scene objects, for placing the camera (Frame object, orbit limits, a new
// object kept in view). The server reports no mesh bounds (GET /api/assets lists ids only), so
// the built-ins' radii at scale 1 come from renderer/src/assets/meshes.cpp: all are centred on their
// origin; the sphere, torus (0.7 + 0.3) and teapot (scaled to it) reach radius 1, the plane and
// the cube span -1..1 (radius sqrt 2, sqrt 3). An uploaded OBJ keeps its own coordinates, which
// the UI does not know: it is taken as centred with radius 1.75.
export const MESH_RADIUS = { sphere: 1, dense_sphere: 1, torus: 1, teapot: 1, plane: Math.SQRT2, cube: Math.sqrt(3) };
export const UPLOAD_RADIUS = 1.75;

/** {center, radius} of a scene object: the mesh's radius times its largest scale (rotation about
 *  the mesh's own centre leaves a centred sphere where it is). */
export function boundingSphere(object) {
  const scale = (object?.scale || [1, 1, 1]).map(Math.abs);
  return {
    center: (object?.translate || [0, 0, 0]).slice(),
    radius: (MESH_RADIUS[object?.mesh] ?? UPLOAD_RADIUS) * Math.max(...scale),
  };
}
