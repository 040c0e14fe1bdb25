//! The guided session in an async task (feature `async`): a sensor read with `.await` (an
//! `embedded-hal-async` driver, an Embassy task), and the solve in bounded steps that yield to the
//! executor between GA generations, so that a calibration never holds the executor for more than one
//! generation (about 60 k cycles on a Cortex-M4F at population 40 and 24 poses).
//!
//! ```
//! use accelcal::calibrate::DefaultRng;
//! use accelcal::session::{RunLimits, Session, SessionConfig};
//! use accelcal::session_async::AsyncAccelSensor;
//! use rand_core::SeedableRng;
//!
//! struct Driver; // e.g. an embedded-hal-async I2C driver
//! impl AsyncAccelSensor for Driver {
//!     type Error = ();
//!     async fn read_raw(&mut self) -> Result<[i16; 3], ()> {
//!         Err(()) // await the bus here
//!     }
//! }
//!
//! async fn calibrate_task(session: &mut Session<i16, 24, 32, 40>) {
//!     let mut imu = Driver;
//!     let rng = DefaultRng::seed_from_u64(1);
//!     let _ = session.run_with_sensor_async(&mut imu, rng, &RunLimits::DEFAULT, |_| core::ops::ControlFlow::Continue(())).await;
//! }
//! ```

use core::future::Future;
use core::ops::ControlFlow;
use core::pin::Pin;
use core::task::{Context, Poll};

use rand_core::Rng;

use crate::calibrate::Step;
use crate::session::{Progress, RunError, RunLimits, Session, SessionResult};

/// A sensor read with `.await`: the async twin of [`crate::sensor::AccelSensor`].
#[allow(async_fn_in_trait)] // single-threaded firmware executors need no `Send` bound
pub trait AsyncAccelSensor {
    /// The driver's error.
    type Error;
    /// One raw sample (x, y, z counts).
    async fn read_raw(&mut self) -> Result<[i16; 3], Self::Error>;
}

/// Returns `Pending` once (waking itself), so that other tasks run.
struct YieldNow(bool);

impl Future for YieldNow {
    type Output = ();

    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<()> {
        if self.0 {
            return Poll::Ready(());
        }
        self.0 = true;
        cx.waker().wake_by_ref();
        Poll::Pending
    }
}

/// Lets the executor run other tasks once.
pub async fn yield_now() {
    YieldNow(false).await;
}

impl<const POSES: usize, const BLOCK: usize, const POP: usize> Session<i16, POSES, BLOCK, POP> {
    /// [`Session::run_with_sensor`] with an async sensor: reads are awaited, and the solve runs in
    /// [`Session::begin_finish`] steps with a yield to the executor between them. Same limits, same
    /// errors, same result for the same samples and seed.
    pub async fn run_with_sensor_async<S: AsyncAccelSensor, G: Rng>(
        &mut self,
        sensor: &mut S,
        rng: G,
        limits: &RunLimits,
        mut on_progress: impl FnMut(&Progress) -> ControlFlow<()>,
    ) -> Result<SessionResult, RunError<S::Error>> {
        let mut consecutive_errors = 0u32;
        for _ in 0..limits.max_samples {
            let read = sensor.read_raw().await;
            let Some(progress) = self.take_read(read, &mut consecutive_errors, limits)? else { break };
            if on_progress(&progress).is_break() {
                break;
            }
        }
        Ok(self.finish_async(rng).await?)
    }

    /// [`Session::finish`], yielding to the executor after every GA generation.
    pub async fn finish_async<G: Rng>(&mut self, rng: G) -> Result<SessionResult, crate::session::SessionError> {
        let mut calibrator = self.begin_finish(rng)?;
        let calibration = loop {
            match calibrator.step(self.poses()) {
                Ok(Step::Running { .. }) => yield_now().await,
                Ok(Step::Finished(calibration)) => break Ok(calibration),
                Err(e) => break Err(e),
            }
        };
        self.conclude(calibration)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::{SessionConfig, State};
    use core::task::Waker;
    use rand_core::SeedableRng;

    /// A minimal executor: polls until ready, counting the polls.
    fn block_on<F: Future>(future: F) -> (F::Output, u32) {
        // A waker that does nothing: the loop polls again anyway.
        let mut cx = Context::from_waker(Waker::noop());
        let mut future = core::pin::pin!(future);
        let mut polls = 0;
        loop {
            polls += 1;
            if let Poll::Ready(v) = future.as_mut().poll(&mut cx) {
                return (v, polls);
            }
        }
    }

    /// The sync session test's hand: free directions, 500 reads each, 50 of motion.
    struct Hand {
        read: u32,
    }

    impl Hand {
        fn sample(&mut self) -> [i16; 3] {
            const H: f32 = core::f32::consts::FRAC_1_SQRT_2;
            let dirs = [
                [0.0f32, 0.0, 1.0],
                [0.0, 0.0, -1.0],
                [1.0, 0.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, -1.0, 0.0],
                [0.577_350_3, 0.577_350_3, 0.577_350_3],
                [-0.577_350_3, 0.577_350_3, -0.577_350_3],
                [0.577_350_3, -0.577_350_3, -0.577_350_3],
                [-0.577_350_3, -0.577_350_3, 0.577_350_3],
                [H, H, 0.0],
                [0.0, H, -H],
                [-H, 0.0, H],
            ];
            self.read += 1;
            let (pose, at) = ((self.read / 550) as usize % dirs.len(), self.read % 550);
            let moving = if at >= 500 { (at - 500) as f32 * 60.0 } else { 0.0 };
            let wobble = (self.read.wrapping_mul(2_654_435_761) >> 28) as f32 - 8.0;
            core::array::from_fn(|a| (dirs[pose][a] * 16384.0 * 0.98 + 150.0 + wobble + moving) as i16)
        }
    }

    impl AsyncAccelSensor for Hand {
        type Error = ();
        async fn read_raw(&mut self) -> Result<[i16; 3], ()> {
            yield_now().await; // as a bus transfer would
            Ok(self.sample())
        }
    }

    impl crate::sensor::AccelSensor for Hand {
        type Error = ();
        fn read_raw(&mut self) -> Result<[i16; 3], ()> {
            Ok(self.sample())
        }
    }

    #[test]
    fn the_async_run_equals_the_sync_run_and_yields_between_generations() {
        let config = SessionConfig { min_poses: 12, hold_samples: 400, ..SessionConfig::DEFAULT };
        let limits = RunLimits { max_samples: 13 * 550, ..RunLimits::DEFAULT };
        let seed = 4;
        let mut sync_session: Session<i16, 24, 32, 40> = Session::new(config).unwrap();
        let rng = crate::calibrate::DefaultRng::seed_from_u64(seed);
        let sync = sync_session.run_with_sensor(&mut Hand { read: 0 }, rng, &limits, |_| ControlFlow::Continue(()));
        let mut async_session: Session<i16, 24, 32, 40> = Session::new(config).unwrap();
        let rng = crate::calibrate::DefaultRng::seed_from_u64(seed);
        let mut hand = Hand { read: 0 };
        let (asynchronous, polls) =
            block_on(async_session.run_with_sensor_async(&mut hand, rng, &limits, |_| ControlFlow::Continue(())));
        let sync = sync.unwrap();
        assert_eq!(asynchronous.unwrap(), sync);
        assert_eq!(async_session.state(), State::Done);
        // One poll per read, and one per GA generation.
        assert!(polls >= limits.max_samples + sync.calibration.generations, "{polls}");
    }
}
