//! The model file: safetensors, so that anyone can open it from Python, with JSON metadata
//! that records everything inference needs.
//!
//! Tensors, per network: `OBJECT/COMPONENT/w1` [20, 13], `b1` [20], `w2` [10, 20], `b2` [10],
//! `w3` [3, 10], `b3` [3], all f32. A network of a leaf of the object's kd-tree
//! ([`crate::partition`]) has its region's splits in the name: `OBJECT/COMPONENT/x<0.25/w1`.
//! The metadata key `rrf` holds [`Metadata`] as JSON: the format version, the scene's
//! content hash, per network its region, input ranges, target transform and training
//! statistics, the bake settings, and a checksum of the tensor data.
//! Nothing in the file depends on when or how fast it was baked (no timings, no dates), so
//! the same scene, settings and seed give the same bytes: an interrupted and resumed bake is
//! byte-identical to an uninterrupted one.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use glam::Vec3;
use safetensors::tensor::{Dtype, TensorView};
use safetensors::SafeTensors;
use serde::{Deserialize, Serialize};

use crate::atomic_file::write_atomically;
use crate::hash::Fnv64;
use crate::network::{Component, Network, B1, B2, B3, HIDDEN1, HIDDEN2, INPUTS, OUTPUTS, PARAMETERS, W1, W2, W3};
use crate::partition::{is_partition, Region, Split, MAX_BLEND_BAND};
use crate::scene::Scene;

/// Version 4: an object's component may have several networks, one per leaf of a kd-tree over
/// position (`region` in [`NetworkInfo`], the splits in the tensor names). Version 3: the
/// networks give radiance over the surface's reflectance ([`crate::network::reflectance`]),
/// which the renderer multiplies back. Version 2: the scene
/// hash covers only what shapes the samples (not the views), and no timings are recorded.
/// Older models are refused with a message to re-bake.
pub const FORMAT_VERSION: u32 = 4;

/// The names of the 13 inputs, in order.
pub const INPUT_NAMES: [&str; INPUTS] = [
    "position.x",
    "position.y",
    "position.z",
    "to_viewer.x",
    "to_viewer.y",
    "to_viewer.z",
    "light.x",
    "light.y",
    "light.z",
    "normal.x",
    "normal.y",
    "normal.z",
    "roughness",
];

/// The tensors of one network: name, shape, offset in the parameter vector.
const TENSORS: [(&str, [usize; 2], usize); 6] = [
    ("w1", [HIDDEN1, INPUTS], W1),
    ("b1", [HIDDEN1, 1], B1),
    ("w2", [HIDDEN2, HIDDEN1], W2),
    ("b2", [HIDDEN2, 1], B2),
    ("w3", [OUTPUTS, HIDDEN2], W3),
    ("b3", [OUTPUTS, 1], B3),
];

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metadata {
    pub format_version: u32,
    pub scene: String,
    /// [`Scene::content_hash`] in hex.
    pub scene_hash: String,
    pub inputs: Vec<String>,
    pub layers: Vec<usize>,
    pub activation: String,
    pub networks: Vec<NetworkInfo>,
    /// Objects that got no network, and why. They render black.
    pub untrained: Vec<Untrained>,
    /// Objects whose networks also learned their neighbours' samples, being short of their
    /// own, and from where: their light is an approximation.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub borrowed: Vec<Untrained>,
    /// The settings the model was baked with.
    pub bake: serde_json::Value,
    /// The half-width of the band around each kd-tree cut across which the leaves that meet
    /// there are blended, as a share of a leaf's extent along the cut
    /// ([`crate::partition::BlendBox`]); 0 (and absent, in models baked before blending):
    /// hard cuts.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub blend_band: f32,
    /// FNV-1a 64 of all tensor data in the order of `networks`, in hex.
    pub checksum: String,
}

fn is_zero(v: &f32) -> bool {
    *v == 0.0
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NetworkInfo {
    pub object: String,
    pub component: Component,
    /// The kd-tree leaf the network covers; absent when it covers the whole object.
    #[serde(default, skip_serializing_if = "Region::is_whole")]
    pub region: Region,
    pub input_min: Vec<f32>,
    pub input_max: Vec<f32>,
    /// `scale`: the network predicts radiance / `output_scale`.
    pub target_transform: String,
    pub output_scale: f32,
    pub samples: usize,
    pub train_mse: f64,
    pub val_mse: f64,
    /// The validation targets' own noise (mean estimated variance): the `val_mse` of a
    /// perfect fit.
    pub val_noise: f64,
    pub iterations: u32,
}

impl NetworkInfo {
    /// The network this describes, with parameters `params`, blended across its cuts over
    /// `blend_band` ([`Metadata::blend_band`]); `None` unless there are 13 input ranges of
    /// each kind and the parameters of one network.
    pub fn network(&self, params: Vec<f32>, blend_band: f32) -> Option<Network> {
        if self.input_min.len() != INPUTS || self.input_max.len() != INPUTS || params.len() != PARAMETERS {
            return None;
        }
        // The position inputs' ranges are the object's bounding box, the kd-tree's root.
        let corner = |v: &[f32]| Vec3::new(v[0], v[1], v[2]);
        Some(Network {
            object: self.object.clone(),
            component: self.component,
            region: self.region.clone(),
            blend: self.region.blend_box(corner(&self.input_min), corner(&self.input_max), blend_band),
            input_min: std::array::from_fn(|i| self.input_min[i]),
            input_max: std::array::from_fn(|i| self.input_max[i]),
            output_scale: self.output_scale,
            params,
        })
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Untrained {
    pub object: String,
    pub samples: usize,
    pub reason: String,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    pub metadata: Metadata,
    pub networks: Vec<Network>,
}

#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", file.display())]
pub struct ModelError {
    pub file: PathBuf,
    pub problem: String,
}

/// The tensor names' prefix for a network: `OBJECT/COMPONENT` and its region's splits.
fn tensor_prefix(object: &str, component: Component, region: &Region) -> String {
    format!("{object}/{}{}", component.name(), region.path())
}

fn tensor_bytes(network: &Network) -> Vec<u8> {
    network.params.iter().flat_map(|v| v.to_le_bytes()).collect()
}

impl Model {
    /// Whether the model has networks for `object`'s `component`.
    pub fn has(&self, object: &str, component: Component) -> bool {
        self.networks.iter().any(|n| n.object == object && n.component == component)
    }

    /// The networks of `object`'s `component`: one, or one per leaf of its kd-tree.
    pub fn networks(&self, object: &str, component: Component) -> Vec<&Network> {
        self.networks.iter().filter(|n| n.object == object && n.component == component).collect()
    }

    pub fn to_bytes(&self) -> Result<Vec<u8>, String> {
        let mut metadata = self.metadata.clone();
        let mut hash = Fnv64::default();
        let params: Vec<Vec<u8>> = self.networks.iter().map(tensor_bytes).collect();
        params.iter().for_each(|p| hash.write(p));
        metadata.checksum = format!("{:016x}", hash.0);
        let mut views = Vec::new();
        for (network, bytes) in self.networks.iter().zip(&params) {
            for (name, shape, offset) in TENSORS {
                let len = shape[0] * shape[1] * 4;
                let data = &bytes[offset * 4..offset * 4 + len];
                let shape = if shape[1] == 1 { vec![shape[0]] } else { shape.to_vec() };
                let view = TensorView::new(Dtype::F32, shape, data).map_err(|e| e.to_string())?;
                let prefix = tensor_prefix(&network.object, network.component, &network.region);
                views.push((format!("{prefix}/{name}"), view));
            }
        }
        let json = serde_json::to_string(&metadata).map_err(|e| e.to_string())?;
        safetensors::serialize(views, Some(HashMap::from([("rrf".to_string(), json)]))).map_err(|e| e.to_string())
    }

    pub fn save(&self, path: &Path) -> Result<(), ModelError> {
        let fail = |problem: String| ModelError { file: path.to_path_buf(), problem };
        let bytes = self.to_bytes().map_err(fail)?;
        // An interrupted or failed save (a full disk) never leaves a broken model, and leaves
        // the model that was there before untouched.
        write_atomically(path, |tmp| std::fs::write(tmp, bytes)).map_err(|e| fail(format!("cannot write: {e}")))
    }

    /// Loads and checks a model; with `scene`, also that it was baked from that scene.
    pub fn load(path: &Path, scene: Option<&Scene>) -> Result<Self, ModelError> {
        let fail = |problem: String| ModelError { file: path.to_path_buf(), problem };
        let bytes = std::fs::read(path).map_err(|e| {
            fail(match e.kind() {
                std::io::ErrorKind::NotFound => "no such model file; bake one with `rrf bake SCENE`".to_string(),
                _ => format!("cannot read: {e}"),
            })
        })?;
        let model = Self::from_bytes(&bytes).map_err(fail)?;
        if let Some(scene) = scene {
            let hash = format!("{:016x}", scene.content_hash);
            if model.metadata.scene_hash != hash {
                return Err(fail(format!(
                    "baked from scene {:?} (content hash {}), but {} has content hash {hash}: the scene changed \
                     or this model belongs to another scene; re-bake with `rrf bake {}`",
                    model.metadata.scene,
                    model.metadata.scene_hash,
                    scene.gltf_path.display(),
                    scene.gltf_path.parent().unwrap_or(Path::new(".")).display()
                )));
            }
            for n in &model.networks {
                if scene.object_by_name(&n.object).is_none() {
                    return Err(fail(format!(
                        "has a network for object {:?}, which the scene does not have",
                        n.object
                    )));
                }
            }
        }
        Ok(model)
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Self, String> {
        let tensors = SafeTensors::deserialize(bytes)
            .map_err(|e| format!("not a valid model file (truncated or corrupted safetensors: {e})"))?;
        let (_, header) = SafeTensors::read_metadata(bytes).map_err(|e| format!("unreadable header: {e}"))?;
        let json = header
            .metadata()
            .as_ref()
            .and_then(|m| m.get("rrf"))
            .ok_or("a safetensors file, but not an rrf model (no `rrf` metadata)")?;
        let version: serde_json::Value = serde_json::from_str(json).map_err(|e| format!("broken metadata: {e}"))?;
        match version.get("format_version").and_then(|v| v.as_u64()) {
            Some(v) if v == u64::from(FORMAT_VERSION) => {}
            Some(v) => {
                return Err(format!(
                    "model format version {v}, but this rrf reads version {FORMAT_VERSION}; re-bake the model"
                ))
            }
            None => return Err("metadata has no format_version".into()),
        }
        let metadata: Metadata = serde_json::from_value(version).map_err(|e| format!("broken metadata: {e}"))?;
        if metadata.layers != [HIDDEN1, HIDDEN2, OUTPUTS] || metadata.inputs.len() != INPUTS {
            return Err(format!(
                "network shape {:?} with {} inputs is not 13 → 20 → 10 → 3",
                metadata.layers,
                metadata.inputs.len()
            ));
        }
        if !(0.0..=MAX_BLEND_BAND).contains(&metadata.blend_band) {
            return Err(format!("blend_band {} is outside [0, {MAX_BLEND_BAND}]", metadata.blend_band));
        }
        let mut hash = Fnv64::default();
        let mut networks = Vec::new();
        for info in &metadata.networks {
            let mut params = vec![0.0f32; PARAMETERS];
            if !info.region.is_valid() {
                return Err(format!(
                    "network {}/{}: a region's split is not on axis 0-2 at a finite position",
                    info.object,
                    info.component.name()
                ));
            }
            let prefix = tensor_prefix(&info.object, info.component, &info.region);
            for (name, shape, offset) in TENSORS {
                let key = format!("{prefix}/{name}");
                let t = tensors.tensor(&key).map_err(|_| format!("tensor {key} is missing"))?;
                let expected: Vec<usize> = if shape[1] == 1 { vec![shape[0]] } else { shape.to_vec() };
                if t.dtype() != Dtype::F32 || t.shape() != expected.as_slice() {
                    return Err(format!("tensor {key} is {:?} {:?}, expected F32 {expected:?}", t.dtype(), t.shape()));
                }
                for (i, chunk) in t.data().chunks_exact(4).enumerate() {
                    params[offset + i] = f32::from_le_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]);
                }
            }
            let name = format!("network {prefix}");
            let network = info
                .network(params, metadata.blend_band)
                .ok_or_else(|| format!("{name}: input ranges must have 13 entries"))?;
            if info.target_transform != "scale" || !(info.output_scale.is_finite() && info.output_scale > 0.0) {
                return Err(format!("{name}: unknown target transform"));
            }
            if !info.input_min.iter().zip(&info.input_max).all(|(lo, hi)| lo.is_finite() && hi.is_finite() && lo <= hi)
            {
                return Err(format!("{name}: input ranges must be finite with min ≤ max"));
            }
            if let Some(i) = network.params.iter().position(|p| !p.is_finite()) {
                return Err(format!("{name}: parameter {i} is not finite; re-bake the model"));
            }
            hash.write(&tensor_bytes(&network));
            networks.push(network);
        }
        let mut trees: BTreeMap<(&str, &str), Vec<&[Split]>> = BTreeMap::new();
        for info in &metadata.networks {
            trees.entry((&info.object, info.component.name())).or_default().push(&info.region.0);
        }
        for ((object, component), regions) in &trees {
            if !is_partition(regions) {
                return Err(format!(
                    "the {} networks of {object}/{component} are not the leaves of one kd-tree (a gap or an overlap)",
                    regions.len()
                ));
            }
        }
        if format!("{:016x}", hash.0) != metadata.checksum {
            return Err("corrupted: the tensor data does not match the checksum recorded when it was baked".into());
        }
        Ok(Model { metadata, networks })
    }
}
