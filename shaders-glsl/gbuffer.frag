#version 450
// G-buffer pass, fragment stage: what the network inputs and the composite need.
// The shading normal faces the viewer, as the path tracer's does; emission shows only on
// the front face (all rrf materials are single-sided emitters).

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_emission_roughness;
layout(location = 3) flat in uint in_object;

layout(location = 0) out vec4 out_position_roughness;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out uint out_object;
layout(location = 3) out vec4 out_emission;

void main() {
    vec3 n = normalize(in_normal);
    out_normal = vec4(gl_FrontFacing ? n : -n, 0.0);
    out_position_roughness = vec4(in_position, in_emission_roughness.w);
    // Object ids are stored +1 so that 0 means "nothing here".
    out_object = in_object + 1u;
    out_emission = vec4(gl_FrontFacing ? in_emission_roughness.rgb : vec3(0.0), 1.0);
}
