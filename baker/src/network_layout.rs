// The network's shape and parameter layout: the one definition that the baker
// (`network.rs`), the renderer (`passes/network/`, through `include!`) and the shaders
// (build.rs writes these as `network_layout.glsl`) all use. Plain constants only, so that a
// build script can include the file.

/// Network inputs: position, direction to the viewer, light position, normal (3 each) and
/// roughness.
pub const INPUTS: usize = 13;
/// Where the direction to the viewer's x, y, z sit among the inputs.
pub const VIEW_INPUT: usize = 3;
/// Where the light position's x, y, z sit among the inputs. The renderer sums the networks
/// over several lights by re-evaluating only these three inputs' share of the first layer.
pub const LIGHT_INPUT: usize = 6;
/// Units of the first hidden layer (tanh).
pub const HIDDEN1: usize = 20;
/// Units of the second hidden layer (tanh).
pub const HIDDEN2: usize = 10;
/// Outputs: linear RGB.
pub const OUTPUTS: usize = 3;

/// Parameter offsets, in this order: w1 [HIDDEN1][INPUTS] row-major, b1 [HIDDEN1],
/// w2 [HIDDEN2][HIDDEN1], b2 [HIDDEN2], w3 [OUTPUTS][HIDDEN2], b3 [OUTPUTS].
pub const W1: usize = 0;
pub const B1: usize = W1 + HIDDEN1 * INPUTS;
pub const W2: usize = B1 + HIDDEN1;
pub const B2: usize = W2 + HIDDEN2 * HIDDEN1;
pub const W3: usize = B2 + HIDDEN2;
pub const B3: usize = W3 + OUTPUTS * HIDDEN2;
/// Parameters of one network.
pub const PARAMETERS: usize = B3 + OUTPUTS;

/// The least reflectance (`network::reflectance`) the networks' targets are divided by, so
/// that black surfaces do not divide by zero.
pub const MIN_REFLECTANCE: f32 = 0.01;

/// Floats per network unit (a part of an object with one direct and one indirect network) in
/// the renderer's storage variant: the direct, then the indirect parameters, each with its input
/// normalisation and output scale folded in.
pub const UNIT_STRIDE: usize = 2 * PARAMETERS;
/// Floats per unit in the renderer's unit table: for its direct, then its indirect network,
/// the blend box of its kd-tree leaf (`partition::BlendBox`): min xyz, max xyz, the bands
/// around the min faces, then around the max faces.
pub const UNIT_BLEND: usize = 24;
/// Specialization constant id of the first direct parameter of the renderer's specialized
/// variant; the indirect network's follow the direct's. Ids below it are the shader's own.
pub const FIRST_PARAMETER_ID: usize = 16;
