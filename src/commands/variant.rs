//! `--variant`: how the networks reach the shader, for `rrf render` and `rrf bench`.

use clap::builder::PossibleValue;
use clap::ValueEnum;
use rrf_renderer::passes::network::Variant;

/// A network pass variant as a command-line value; the help lists what each one does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VariantArg(pub Variant);

impl VariantArg {
    /// The fastest variant on lavapipe (BENCHMARKS.md) and on the GPUs measured so far.
    pub const DEFAULT: VariantArg = VariantArg(Variant::Tiled);
}

impl ValueEnum for VariantArg {
    fn value_variants<'a>() -> &'a [Self] {
        &[VariantArg(Variant::Tiled), VariantArg(Variant::PerObject), VariantArg(Variant::Storage)]
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        let help = match self.0 {
            Variant::Tiled => {
                "one pipeline per object (per part, for objects the bake split) with its weights as \
                 specialization constants, dispatched over only the 8x8 tiles it covers (default)"
            }
            Variant::PerObject => "the same pipelines, each dispatched over the whole image",
            Variant::Storage => {
                "one pipeline; every object's weights in a storage buffer, the part of a split object \
                 found per pixel"
            }
        };
        Some(PossibleValue::new(self.0.name()).help(help))
    }
}
