use std::path::{Path, PathBuf};

/// A problem with a scene file, naming the file and the element (node, mesh, accessor, key).
#[derive(Debug, thiserror::Error)]
#[error("{}: {}", file.display(), describe(element, problem))]
pub struct SceneError {
    pub file: PathBuf,
    /// Where in the file, for example `nodes[3] "Lamp"` or `light.min`; empty for the file
    /// as a whole.
    pub element: String,
    pub problem: String,
}

fn describe(element: &str, problem: &str) -> String {
    if element.is_empty() {
        problem.to_string()
    } else {
        format!("{element}: {problem}")
    }
}

/// How errors name a glTF element: `nodes[3] "Lamp"`, or `nodes[3]` when it has no name.
pub(super) fn element_name(kind: &str, index: usize, name: Option<&str>) -> String {
    match name {
        Some(name) => format!("{kind}[{index}] {name:?}"),
        None => format!("{kind}[{index}]"),
    }
}

impl SceneError {
    pub fn new(file: &Path, element: impl Into<String>, problem: impl Into<String>) -> Self {
        Self { file: file.to_path_buf(), element: element.into(), problem: problem.into() }
    }
}
