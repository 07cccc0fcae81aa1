//! Reading and validating a model file into a [`Model`]: every item checked
//! ([`Model::check`]'s rules), then the mechanism check, which compiles the model's
//! [`Structure`] and factorises its stiffness. Beside `model` rather than inside it: the
//! compiler reads the model, and this reads the compiler.

use crate::model::Model;
use crate::model_file::ModelFile;
use crate::{ModelError, Structure};
use std::path::Path;

impl Model {
    /// Reads and validates a model file.
    pub fn read(path: &Path) -> Result<Self, ModelError> {
        use crate::model_file::{ReadFailure, read_input};
        let text = read_input(path).map_err(|e| match e {
            ReadFailure::Io(source) => ModelError::Io {
                path: path.to_path_buf(),
                source,
            },
            ReadFailure::Refused(reason) => ModelError::Refused {
                path: path.to_path_buf(),
                reason,
            },
        })?;
        Self::from_json(&text, &path.display().to_string())
    }

    /// Parses and validates a model file's text; `origin` names it in errors.
    pub fn from_json(text: &str, origin: &str) -> Result<Self, ModelError> {
        Self::new(ModelFile::from_json(text, origin)?)
    }

    /// Validates a model file.
    pub fn new(file: ModelFile) -> Result<Self, ModelError> {
        let model = Self::check(file)?;
        Structure::new(&model)?;
        Ok(model)
    }
}

#[cfg(test)]
mod tests {
    use crate::prism::{BacklashOptions, PrismOptions};

    /// Finite but implausible magnitudes (1e308 passes `is_finite`) are refused by item and
    /// field: a coordinate, an area, a modulus, a load, a joint clearance.
    #[test]
    fn implausible_magnitudes_are_refused_by_field() {
        let prism = || PrismOptions::with_stages(1).file().unwrap();
        let message = |f| crate::Model::new(f).unwrap_err().to_string();
        let mut f = prism();
        f.nodes[4].xyz[2] = 1e308;
        let m = message(f);
        assert!(m.starts_with("nodes[4] (id \"n1.1\"): xyz 1e308"), "{m}");
        let mut f = prism();
        f.members[0].area = 1e308;
        assert!(message(f).contains("members[0] (id \"batten.0.0\"): area 1e308"));
        let mut f = prism();
        f.members[3].youngs_modulus = 1e308;
        assert!(message(f).contains("youngs_modulus 1e308"));
        let mut f = prism();
        f.loads.push(crate::model_file::LoadSpec {
            node: "n1.0".into(),
            force: [0.0, 0.0, -1e308],
        });
        assert!(message(f).contains("loads[0]: force -1e308"));
        let mut f = PrismOptions {
            backlash: Some(BacklashOptions::default()),
            ..PrismOptions::with_stages(1)
        }
        .file()
        .unwrap();
        f.joints[0].clearance = 40.0;
        let m = message(f);
        assert!(
            m.contains("joints[0]") && m.contains("clearance 40 mm"),
            "{m}"
        );
    }
}
