// Names a BRDFA Engine render() file reads besides iParameter0..8 (which are its parameters):
// the engine bound its cube-map environment as `skybox`. Directions reaching render() are in
// the environment's frame (lib/environment.glsl), so the file's texture(skybox, L) reads the
// radiance arriving from L at intensity 1, as brdfa_environmentUnit() does. Declared here,
// before the file's text, at the environment's binding (lib/bindings.glsl names it again as
// brdfa_envMap, after the file): the file sees the environment and nothing else of the
// integrator's.
layout(set = 0, binding = 5) uniform samplerCube skybox;
