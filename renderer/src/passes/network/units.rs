//! Network units (an object's part with one direct and one indirect network), the unit table
//! the shaders read, and the specialization constants of each unit's pipelines.

use super::interface::{
    ANALYTIC_ID, OBJECTS_ID, OBJECT_FIRST_UNIT_ID, OBJECT_ID, SEVERAL_LIGHTS_ID, TILED_ID, UNIT_ID,
};
use super::layout::{FIRST_PARAMETER_ID, PARAMETERS, UNIT_BLEND};
use super::weights::NetworkWeights;
use crate::backend::compute::Specialization;
use crate::error::{Error, Result};

/// A part of object id `object` with one direct and one indirect network, whose weight at a
/// point is the product of the two networks' [`LeafBlend`] weights there. The weights of an
/// object's units must sum to one everywhere (every pair of a direct and an indirect leaf of
/// two kd-trees whose supports meet), so that a pixel's radiance is their weighted sum.
#[derive(Clone, Copy)]
pub struct NetworkUnit<'a> {
    pub object: usize,
    pub direct: NetworkWeights<'a>,
    pub indirect: NetworkWeights<'a>,
}

impl NetworkUnit<'_> {
    /// Whether the unit blends with another somewhere: then the pass must write radiance
    /// images, not a display image.
    pub fn blends(&self) -> bool {
        self.direct.blend.has_band() || self.indirect.blend.has_band()
    }

    fn check(&self, objects: usize) -> Result<()> {
        if self.direct.params.len() != PARAMETERS || self.indirect.params.len() != PARAMETERS {
            return Err(Error::Invalid(format!("object {}: a network must have {PARAMETERS} parameters", self.object)));
        }
        if self.object >= objects {
            return Err(Error::Invalid(format!("a network unit of object {}, of {objects} objects", self.object)));
        }
        Ok(())
    }
}

/// The units in the order the pass uses (grouped by object, which the unit table needs),
/// checked against `objects` object ids.
pub(super) fn ordered<'a>(objects: usize, units: &[NetworkUnit<'a>]) -> Result<Vec<NetworkUnit<'a>>> {
    units.iter().try_for_each(|u| u.check(objects))?;
    let mut ordered = units.to_vec();
    ordered.sort_by_key(|u| u.object);
    Ok(ordered)
}

/// The table of `network_units.glsl` for `units` (grouped by object) of `objects` object ids:
/// per object its first unit and unit count, then per unit its two leaves' blend boxes.
pub(super) fn unit_table(objects: usize, units: &[NetworkUnit]) -> Vec<f32> {
    let mut table = vec![0.0f32; 2 * objects.max(1)];
    for (index, unit) in units.iter().enumerate() {
        let entry = &mut table[2 * unit.object..2 * unit.object + 2];
        if entry[1] == 0.0 {
            entry[0] = index as f32;
        }
        entry[1] += 1.0;
    }
    for unit in units {
        table.extend(unit.direct.blend.table().chain(unit.indirect.blend.table()));
    }
    debug_assert_eq!(table.len(), 2 * objects.max(1) + UNIT_BLEND * units.len());
    table
}

/// Specialization constants of the two pipelines of unit `index` of `units` (grouped by
/// object, of `objects` object ids), for frames of one light and of several (see
/// `network_specialized_main.glsl`).
pub(super) fn specializations(
    objects: usize,
    units: &[NetworkUnit],
    index: usize,
    tiled: bool,
    analytic: bool,
) -> [Specialization; 2] {
    let unit = &units[index];
    let mut words = vec![0u32; FIRST_PARAMETER_ID + 2 * PARAMETERS];
    let first_unit = units.iter().position(|u| u.object == unit.object).expect("the unit itself");
    for (id, value) in [
        (OBJECT_ID, unit.object as u32 + 1),
        (TILED_ID, u32::from(tiled)),
        (ANALYTIC_ID, u32::from(analytic)),
        (UNIT_ID, index as u32),
        (OBJECT_FIRST_UNIT_ID, first_unit as u32),
        (OBJECTS_ID, objects.max(1) as u32),
    ] {
        words[id as usize] = value;
    }
    let (direct, indirect) = (unit.direct.folded(), unit.indirect.folded());
    for (word, value) in words[FIRST_PARAMETER_ID..].iter_mut().zip(direct.iter().chain(&indirect)) {
        *word = value.to_bits();
    }
    let mut several = words.clone();
    several[SEVERAL_LIGHTS_ID as usize] = 1;
    [words, several]
}
