#version 450
#extension GL_GOOGLE_include_directive : require
// The specialized network pass writing the direct, indirect and global radiance images
// (rrf render, eval, bench). See network_specialized_main.glsl.

#include "network_specialized_main.glsl"
