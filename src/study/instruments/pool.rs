//! The candidate pool of an instruments study's instrument, its refusal naming the entry.

use super::InstrumentsScenario;
use crate::error::{Error, Result};
use crate::numeric::rng::stream;
use crate::numeric::Real;
use crate::robot::Robot;
use crate::sim::instrument::{instrument_poses, Layout};

impl InstrumentsScenario {
    /// The candidate poses of instrument `ii` on `nominal`, drawn from the study's seed
    /// ([`instrument_poses`]), with their layout and groups. Too few poses on the instrument
    /// (a sphere or socket the arm's draws do not reach) is refused naming the scenario file
    /// and the `[[measurement]]` entry with its line.
    pub(super) fn pool(
        &self,
        nominal: &Robot,
        ii: usize,
    ) -> Result<(Layout, Vec<Vec<Real>>, Vec<usize>)> {
        let mut rng = stream(self.head.seed, &format!("instruments-pool-{ii}"));
        instrument_poses(&self.measurement[ii], nominal, self.candidates, &mut rng).map_err(|e| {
            match e {
                Error::Compute(msg) => {
                    let key = format!("measurement[{ii}]");
                    let text = crate::error::read_text(&self.head.path).unwrap_or_default();
                    Error::toml_file(&self.head.path, &text, &key, &key, msg)
                }
                e => e,
            }
        })
    }
}
