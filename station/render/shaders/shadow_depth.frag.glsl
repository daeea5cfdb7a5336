#version 430
// Depth only: the shadow maps (station/render/gl_shadows.py; no colour attachment) and a mesh's depth
// pre-pass (station/render/gl_passes.py; colour writes off).
void main() {}
