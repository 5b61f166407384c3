//! The chain as copper-rs tasks (`cu29`, its `#[copper_runtime]` over a task
//! graph in RON: `copper/chain<N>.ron`, written by `copper/gen.py`): a
//! source, N − 2 adders and a sink that adds too, so N tasks do the
//! arithmetic of N steps. Task logging is off; the runtime still keeps its
//! copper list and the unified log it needs (a file in the temp folder).

use std::sync::atomic::{AtomicU32, Ordering};

use bincode::{Decode, Encode};
use cu29::prelude::*;
use serde::{Deserialize, Serialize};
use situate_bench::skills::{add_k, LEN};

/// The message: the array passed down the chain.
#[derive(Default, Debug, Clone, Copy, PartialEq, Encode, Decode, Serialize, Deserialize, Reflect)]
pub struct Arr(pub [f32; LEN]);

/// What the last sink received, first element (`f32` bits).
static LAST: AtomicU32 = AtomicU32::new(0);

#[derive(Reflect)]
pub struct Gen {
    t: f32,
}

impl Freezable for Gen {}

impl CuSrcTask for Gen {
    type Resources<'r> = ();
    type Output<'m> = output_msg!(Arr);

    fn new(_config: Option<&ComponentConfig>, _resources: Self::Resources<'_>) -> CuResult<Self> {
        Ok(Gen { t: 0.0 })
    }

    fn process(&mut self, _ctx: &CuContext, output: &mut Self::Output<'_>) -> CuResult<()> {
        self.t += 1.0;
        output.set_payload(Arr([self.t; LEN]));
        Ok(())
    }
}

#[derive(Reflect)]
pub struct Add;

impl Freezable for Add {}

impl CuTask for Add {
    type Resources<'r> = ();
    type Input<'m> = input_msg!(Arr);
    type Output<'m> = output_msg!(Arr);

    fn new(_config: Option<&ComponentConfig>, _resources: Self::Resources<'_>) -> CuResult<Self> {
        Ok(Add)
    }

    fn process(&mut self, _ctx: &CuContext, input: &Self::Input<'_>, output: &mut Self::Output<'_>) -> CuResult<()> {
        if let Some(x) = input.payload() {
            output.set_payload(Arr(add_k(&x.0)));
        }
        Ok(())
    }
}

#[derive(Reflect)]
pub struct Sink;

impl Freezable for Sink {}

impl CuSinkTask for Sink {
    type Resources<'r> = ();
    type Input<'m> = input_msg!(Arr);

    fn new(_config: Option<&ComponentConfig>, _resources: Self::Resources<'_>) -> CuResult<Self> {
        Ok(Sink)
    }

    fn process(&mut self, _ctx: &CuContext, input: &Self::Input<'_>) -> CuResult<()> {
        if let Some(x) = input.payload() {
            let y = add_k(&x.0);
            LAST.store(std::hint::black_box(y)[0].to_bits(), Ordering::Relaxed);
        }
        Ok(())
    }
}

/// A started chain of `n` tasks: one iteration per call. Its unified log
/// goes to `log`.
pub type Iteration = Box<dyn FnMut()>;

mod chain10 {
    use cu29::prelude::*;

    #[allow(unused_imports)]
    use super::{Add, Gen, Sink};

    #[copper_runtime(config = "copper/chain10.ron")]
    struct Chain10 {}

    pub fn start(log: &std::path::Path) -> CuResult<super::Iteration> {
        let app = Chain10::builder().with_log_path(log, Some(64 * 1024 * 1024))?.build()?;
        let mut running = app.start()?;
        Ok(Box::new(move || {
            if let Err(e) = running.run_one_iteration() {
                panic!("copper iteration: {e}");
            }
        }))
    }
}

mod chain100 {
    use cu29::prelude::*;

    #[allow(unused_imports)]
    use super::{Add, Gen, Sink};

    #[copper_runtime(config = "copper/chain100.ron")]
    struct Chain100 {}

    pub fn start(log: &std::path::Path) -> CuResult<super::Iteration> {
        let app = Chain100::builder().with_log_path(log, Some(64 * 1024 * 1024))?.build()?;
        let mut running = app.start()?;
        Ok(Box::new(move || {
            if let Err(e) = running.run_one_iteration() {
                panic!("copper iteration: {e}");
            }
        }))
    }
}

mod chain1000 {
    use cu29::prelude::*;

    #[allow(unused_imports)]
    use super::{Add, Gen, Sink};

    #[copper_runtime(config = "copper/chain1000.ron")]
    struct Chain1000 {}

    pub fn start(log: &std::path::Path) -> CuResult<super::Iteration> {
        let app = Chain1000::builder().with_log_path(log, Some(64 * 1024 * 1024))?.build()?;
        let mut running = app.start()?;
        Ok(Box::new(move || {
            if let Err(e) = running.run_one_iteration() {
                panic!("copper iteration: {e}");
            }
        }))
    }
}

/// The chain lengths with a task graph (`copper/gen.py`).
pub const NS: [usize; 3] = [10, 100, 1000];

/// Starts the chain of `n` tasks, logging to a file in `dir`, and checks one
/// iteration: the sink sees `1 + (n − 1) K`.
pub fn chain(n: usize, dir: &std::path::Path) -> Iteration {
    let log = dir.join(format!("chain{n}.copper"));
    let started = match n {
        10 => chain10::start(&log),
        100 => chain100::start(&log),
        1000 => chain1000::start(&log),
        _ => panic!("no copper task graph for N = {n}"),
    };
    let mut step = match started {
        Ok(step) => step,
        Err(e) => panic!("copper chain of {n}: {e}"),
    };
    LAST.store(0, Ordering::Relaxed);
    step();
    let want = 1.0 + (n - 1) as f32 * situate_bench::skills::K;
    assert_eq!(f32::from_bits(LAST.load(Ordering::Relaxed)), want, "copper chain of {n} did not run");
    step
}
