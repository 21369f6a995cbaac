//! A method made slower on purpose, for the tests of the timing protocol and of baselines:
//! built only with the cargo feature `slowdown`, which the workspace's own tests turn on (a
//! dev-dependency feature of the `shadowbench` package), never in a release build.
//!
//! `SHADOWBENCH_SLOWDOWN=NAME=FACTOR` makes every run of the method `NAME` cost `FACTOR` times
//! its own CPU time: after the method's stages, a stage named [`STAGE_SLOWDOWN`] spins every
//! thread of the rayon pool until, together, they have spent `FACTOR - 1` times the CPU time
//! the method's stages took. Its results are the method's own; only its cost changes, as a
//! regression of the method's code would change it.

use crate::frame::Frame;
use crate::method::{MethodError, ShadowMethod, Visibility};
use instrumentation::Recorder;
use std::time::Duration;

/// The environment variable that names the method to slow down and the factor.
pub const SLOWDOWN_VAR: &str = "SHADOWBENCH_SLOWDOWN";

/// The stage of the added work.
pub const STAGE_SLOWDOWN: &str = "slowdown";

/// A method whose runs cost `factor` times its CPU time.
pub struct Slowed {
    inner: Box<dyn ShadowMethod>,
    factor: f64,
}

/// `method`, called `name`, slowed down when [`SLOWDOWN_VAR`] names it; as it is otherwise. A
/// variable that is set but not `NAME=FACTOR` with a finite factor >= 1 is refused naming it.
pub fn wrap(
    name: &str,
    method: Box<dyn ShadowMethod>,
) -> Result<Box<dyn ShadowMethod>, MethodError> {
    let Ok(value) = std::env::var(SLOWDOWN_VAR) else { return Ok(method) };
    let bad = || MethodError::InvalidOption {
        option: SLOWDOWN_VAR,
        message: format!("`{value}` is not NAME=FACTOR with a finite factor >= 1"),
    };
    let (target, factor) = value.split_once('=').ok_or_else(bad)?;
    let factor: f64 = factor.parse().map_err(|_| bad())?;
    if !(factor.is_finite() && factor >= 1.0) {
        return Err(bad());
    }
    if target != name {
        return Ok(method);
    }
    Ok(Box::new(Slowed { inner: method, factor }))
}

impl ShadowMethod for Slowed {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        self.inner.params()
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        let first = rec.stages.stages.len();
        let v = self.inner.run(frame, rec)?;
        // The CPU time of the method's own stages, the span the measurement engine times.
        let spent: f64 = rec.stages.stages[first..].iter().filter_map(|s| s.cpu_ms).sum();
        let extra = Duration::from_secs_f64(spent.max(0.0) * 1e-3 * (self.factor - 1.0));
        rec.stages.time(STAGE_SLOWDOWN, || {
            let share = extra / rayon::current_num_threads().max(1) as u32;
            rayon::broadcast(|_| spin(share));
        });
        Ok(v)
    }
}

/// Spins this thread until it has run `cpu` of CPU time.
fn spin(cpu: Duration) {
    let Ok(start) = cpu_time::ThreadTime::try_now() else { return };
    let mut x = 1u64;
    while start.try_elapsed().is_ok_and(|t| t < cpu) {
        for _ in 0..1000 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        }
        std::hint::black_box(x);
    }
}
