#version 450
#extension GL_GOOGLE_include_directive : require
// Tile classification for the display network pass (rrf view): background pixels go straight
// to the tonemapped display image. See network_classify.comp.

#define DISPLAY
#include "network_classify_main.glsl"
