#version 430
// Depth only (station/render/gl_shadows.py); no colour attachment.
void main() {}
