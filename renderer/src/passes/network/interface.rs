// What the network shaders and the host agree on: specialization-constant ids and
// descriptor binding numbers. They are defined here only: `build.rs` includes this file and
// writes each constant into the generated `network_interface.glsl` as a `#define`, which
// every network shader uses instead of a number of its own.
//
// Every network shader (classification, storage and specialized variants) binds
// - 0 to 3: the G-buffer's surface, object id, materials and shading;
// - 4: the lights (classification: the units' dispatch arguments);
// - 5: the variant's buffer (storage: the weights; classification and specialized: the
//   tile lists);
// - 6: the mirror weights (`mirror_merge.comp`), read where the G-buffer shows a reflection;
// - from 7: what it writes: the direct, indirect and global radiance images, or the one
//   display image;
// - then the specialized variants' shadow maps, and last the unit table.
//
// Specialization-constant ids are the same in every network shader that has them, below the
// weights' (`FIRST_PARAMETER_ID` in `baker/src/network_layout.rs`).

pub const SURFACE_BINDING: u32 = 0;
pub const ID_BINDING: u32 = 1;
pub const MATERIALS_BINDING: u32 = 2;
pub const SHADING_BINDING: u32 = 3;
pub const LIGHTS_BINDING: u32 = 4;
pub const DISPATCH_BINDING: u32 = 4;
pub const WEIGHTS_BINDING: u32 = 5;
pub const TILES_BINDING: u32 = 5;
pub const MIRROR_BINDING: u32 = 6;
/// The first image the pass writes; the others follow it.
pub const FIRST_OUTPUT_BINDING: u32 = 7;

/// The most planar mirrors a frame shows reflections in: the eyes of their reflected cameras
/// head the lights buffer.
pub const MAX_MIRRORS: u32 = 8;

/// The G-buffer's object value (object id + 1) a specialized pipeline shades.
pub const OBJECT_ID: u32 = 0;
/// Whether a specialized pipeline's dispatch is indirect, over its unit's tiles.
pub const TILED_ID: u32 = 1;
/// Whether direct light is computed rather than learned.
pub const ANALYTIC_ID: u32 = 2;
/// Whether the frame has more than one light.
pub const SEVERAL_LIGHTS_ID: u32 = 3;
/// The unit's index, its object's first unit, and the object entries of the unit table.
pub const UNIT_ID: u32 = 4;
pub const OBJECT_FIRST_UNIT_ID: u32 = 5;
pub const OBJECTS_ID: u32 = 6;
