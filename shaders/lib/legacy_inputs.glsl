// Names a BRDFA Engine render() file reads besides iParameter0..8 (which are its parameters):
// the engine bound its cube-map environment as `skybox`. Directions reaching render() are in
// the environment's frame (lib/environment.glsl), so the file's texture(skybox, L) reads the
// radiance arriving from L at intensity 1, as brdfa_environmentUnit() does.
#define skybox brdfa_envMap
