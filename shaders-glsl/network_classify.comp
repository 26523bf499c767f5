#version 450
#extension GL_GOOGLE_include_directive : require
// Tile classification for the network pass that writes the radiance images (rrf render,
// eval, bench). See network_classify_main.glsl.

#include "network_classify_main.glsl"
