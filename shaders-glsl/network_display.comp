#version 450
#extension GL_GOOGLE_include_directive : require
// The specialized network pass writing only what the window shows: one tonemapped RGBA8
// image (rrf view). See network_specialized_main.glsl.

#define DISPLAY
#include "network_specialized_main.glsl"
