//! The frames a run keeps for its evolution.glb, whatever its length, and a run
//! that makes them as it goes ([`run_with_frames`], the CLI's).

use super::frames::{glb_bytes, Frame, FrameMaker};
use super::run::{run_prepared, JobFailure, JobOutcome, RunEvents};
use super::PreparedJob;
use crate::flow::{Checkpoint, Progress};
use crate::limits::{MAX_EVOLUTION_BYTES, MAX_FRAMES};
use std::sync::atomic::AtomicBool;
use std::sync::mpsc::SyncSender;

/// Checkpoints a run may be ahead of the thread that makes their frames: beyond,
/// the run waits, so that checkpoints made faster than their frames do not pile
/// up in memory.
pub const FRAMES_AHEAD: usize = 4;

/// [`run_prepared`] with each checkpoint made into its frame ([`FrameMaker`]), on a
/// second thread while the run goes on,
/// as the CLI makes its result files: the run's outcome and the frames of its
/// checkpoints in order ([`KeptFrames`]), the last one its final state (also after a failure).
/// `events` hears the run as from [`run_prepared`].
pub fn run_with_frames(
    job: &PreparedJob,
    resume: Option<&Checkpoint>,
    cancel: &AtomicBool,
    events: &mut dyn RunEvents,
) -> (Result<JobOutcome, Box<JobFailure>>, Vec<Frame>) {
    let (result, mut frames) = std::thread::scope(|scope| {
        let (send, receive) = std::sync::mpsc::sync_channel::<Checkpoint>(FRAMES_AHEAD);
        let maker = scope.spawn(move || {
            let (mut maker, mut kept) = (FrameMaker::default(), KeptFrames::default());
            receive.into_iter().for_each(|c| kept.push(maker.make(job, &c)));
            kept.into_frames()
        });
        let mut tee = Tee { events, frames: send };
        let result = run_prepared(job, resume, cancel, &mut tee);
        drop(tee);
        (result, maker.join().expect("the thread making the frames panicked"))
    });
    let last = match &result {
        Ok(o) => &o.last,
        Err(f) => &f.last,
    };
    if frames.last().map(|f| &f.state) != Some(last) {
        frames.push(Frame::of_run(job, last).with_fill());
    }
    (result, frames)
}

/// The events of a run passed on, and its checkpoints also sent to be made into frames.
struct Tee<'a> {
    events: &'a mut dyn RunEvents,
    frames: SyncSender<Checkpoint>,
}

impl RunEvents for Tee<'_> {
    fn progress(&mut self, p: &Progress) {
        self.events.progress(p);
    }

    fn checkpoint(&mut self, c: &Checkpoint) {
        // (the receiver lives until the run ends)
        let _ = self.frames.send(c.clone());
        self.events.checkpoint(c);
    }
}

/// The frames a run keeps for evolution.glb, with memory that does not grow with
/// the run's length: every frame while there are at most `2 ·` [`MAX_FRAMES`] of
/// them in about `2 ·` [`MAX_EVOLUTION_BYTES`] of glb; beyond, every other one is
/// dropped and only every second, fourth, … frame that comes is kept (always the
/// first and the newest), so that evolution.glb's even pick
/// ([`GlbContext::evolution_glb`]) still has twice the frames it shows to choose from.
#[derive(Debug, Default)]
pub struct KeptFrames {
    /// The frames kept, with their place among all frames pushed.
    kept: Vec<(usize, Frame)>,
    /// The newest frame, if not on the stride.
    newest: Option<Frame>,
    pushed: usize,
    stride: usize,
    bytes: usize,
}

impl KeptFrames {
    pub fn push(&mut self, frame: Frame) {
        let k = self.pushed;
        self.pushed += 1;
        self.stride = self.stride.max(1);
        if k % self.stride != 0 {
            self.newest = Some(frame);
            return;
        }
        self.newest = None;
        self.bytes += glb_bytes(&frame.state.mesh);
        self.kept.push((k, frame));
        while self.kept.len() > 2 * MAX_FRAMES || (self.bytes > 2 * MAX_EVOLUTION_BYTES && self.kept.len() > 2) {
            self.stride *= 2;
            let stride = self.stride;
            // the newest off the new stride is kept apart, until a newer one comes
            if self.kept.last().is_some_and(|(k, _)| k % stride != 0) {
                let (_, f) = self.kept.pop().expect("a frame");
                self.bytes -= glb_bytes(&f.state.mesh);
                self.newest = Some(f);
            }
            let mut dropped = 0;
            self.kept.retain(|(k, f)| {
                let keep = k % stride == 0;
                if !keep {
                    dropped += glb_bytes(&f.state.mesh);
                }
                keep
            });
            self.bytes -= dropped;
        }
    }

    /// The newest frame.
    pub fn last(&self) -> Option<&Frame> {
        self.newest.as_ref().or(self.kept.last().map(|(_, f)| f))
    }

    /// The kept frames in order, the newest last.
    pub fn into_frames(self) -> Vec<Frame> {
        let mut frames: Vec<Frame> = self.kept.into_iter().map(|(_, f)| f).collect();
        frames.extend(self.newest);
        frames
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flow::{Checkpoint, MeshData};

    fn frame(iteration: usize) -> Frame {
        let mesh = MeshData { dimension: 2, positions: vec![vec![0.0, 0.0]; 3], elements: vec![], period: None };
        let state = Checkpoint {
            iteration,
            time: 0.0,
            tau: 1.0,
            energy: 0.0,
            mesh,
            stage: 0,
            coarse: false,
            settled_tau: 0.0,
            recent_energies: vec![],
            surgeries: vec![],
        };
        Frame { state, fields: None, fill: None }
    }

    #[test]
    fn kept_frames_stay_bounded_and_keep_the_first_and_the_newest() {
        let mut kept = KeptFrames::default();
        for k in 0..10_007 {
            kept.push(frame(k));
            assert!(kept.kept.len() <= 2 * MAX_FRAMES);
        }
        let frames = kept.into_frames();
        assert_eq!(frames.first().unwrap().state.iteration, 0);
        assert_eq!(frames.last().unwrap().state.iteration, 10_006);
        assert!(frames.len() > MAX_FRAMES, "{} frames", frames.len());
        // evenly spaced, but for the newest
        let gaps: Vec<usize> = frames.windows(2).map(|w| w[1].state.iteration - w[0].state.iteration).collect();
        assert!(gaps[..gaps.len() - 1].iter().all(|&g| g == gaps[0]), "{gaps:?}");
    }
}
