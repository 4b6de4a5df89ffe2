//! The one f32/f64 dispatch of an engine: [`AnyEngine`] holds a system in the
//! precision its scene or saved record names, and [`each_engine!`](crate::each_engine)
//! runs code generic in the precision on it. The run loop and the Python package
//! both go through it.

use super::{BuildError, Engine, Saved};
use crate::scene::{Precision, Scene};

/// An [`Engine`] in either precision. A clone is an independent system.
#[derive(Clone)]
pub enum AnyEngine {
    /// Double precision.
    F64(Engine<f64>),
    /// Single precision.
    F32(Engine<f32>),
}

/// Runs `$body` with `$e` bound to the engine inside an [`AnyEngine`] (or a reference
/// to one) and the type `$t` to its precision (`f64` or `f32`).
#[macro_export]
macro_rules! each_engine {
    ($any:expr, $e:ident, $t:ident => $body:expr) => {
        match $any {
            $crate::sim::AnyEngine::F64($e) => {
                type $t = f64;
                $body
            }
            $crate::sim::AnyEngine::F32($e) => {
                type $t = f32;
                $body
            }
        }
    };
}

impl AnyEngine {
    /// The system of `scene` (its level already applied) in the scene's precision
    /// ([`Engine::new`]).
    pub fn new(scene: &Scene, limit: usize) -> Result<Self, BuildError> {
        Ok(match scene.integrator.precision {
            Precision::F64 => Self::F64(Engine::new(scene, limit)?),
            Precision::F32 => Self::F32(Engine::new(scene, limit)?),
        })
    }

    /// The precision the engine runs in.
    pub fn precision(&self) -> Precision {
        match self {
            Self::F64(_) => Precision::F64,
            Self::F32(_) => Precision::F32,
        }
    }

    /// This system as plain data ([`Engine::save`]).
    pub fn save(&self) -> Saved {
        let precision = self.precision();
        crate::each_engine!(self, e, _T => e.save(precision))
    }

    /// The system [`AnyEngine::save`] saved, in its precision ([`Engine::restore`]).
    pub fn restore(s: &Saved) -> Result<Self, String> {
        Ok(match s.precision {
            Precision::F64 => Self::F64(Engine::restore(s)?),
            Precision::F32 => Self::F32(Engine::restore(s)?),
        })
    }
}

impl From<Engine<f64>> for AnyEngine {
    fn from(e: Engine<f64>) -> Self {
        Self::F64(e)
    }
}

impl From<Engine<f32>> for AnyEngine {
    fn from(e: Engine<f32>) -> Self {
        Self::F32(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use crate::sizing::DEFAULT_LIMIT;

    fn dimer(precision: &str) -> Scene {
        let text = format!(
            "[[particle]]\nposition = [0, 0, 0]\nradius = 1\n\n\
             [[particle]]\nposition = [2.5, 0, 0]\nradius = 1\n\n\
             [[bond]]\nbetween = [0, 1]\n\n\
             [integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 1\n\
             precision = \"{precision}\"\n"
        );
        Scene::parse(&text, "dimer.toml").unwrap()
    }

    /// The bits of a system's positions, in f64.
    fn positions(e: &AnyEngine) -> Vec<u64> {
        use hydrorattle::Real;
        crate::each_engine!(e, e, T => e
            .beads
            .pos
            .iter()
            .flat_map(|&x| T::v3_to_f64(x).map(f64::to_bits))
            .collect())
    }

    /// The engine runs in the scene's precision, steps there, and its saved record
    /// names that precision and restores the same state.
    #[test]
    fn the_scene_picks_the_precision() {
        for (name, precision) in [("f64", Precision::F64), ("f32", Precision::F32)] {
            let mut e = AnyEngine::new(&dimer(name), DEFAULT_LIMIT).unwrap();
            assert_eq!(e.precision(), precision);
            let before = positions(&e);
            crate::each_engine!(&mut e, e, _T => e.step().map(|_| ())).unwrap();
            assert_ne!(positions(&e), before, "{name}: gravity moves the dimer");
            let saved = e.save();
            assert_eq!(saved.precision, precision);
            let back = AnyEngine::restore(&saved).unwrap();
            assert_eq!(back.precision(), precision);
            assert_eq!(positions(&back), positions(&e));
        }
    }
}
