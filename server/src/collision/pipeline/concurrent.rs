//! The pipeline on a thread of its own, as the runtime's collision loop needs it (PAPER §2.3).
//!
//! Callers put moves into a double-buffered front-end queue: they append to the front buffer under
//! a short lock while the pipeline thread works on the back one; at the start of each frame the
//! thread swaps the two. Frames are requested and their reports handed back over channels, so the
//! caller never waits for a frame unless it wants its answer.

use super::{
    CollisionPipeline, Detail, ExactTest, FrameReport, ObjectDesc, ObjectId, PipelineError,
    check_pose, lock,
};
use crossbeam_channel::{Receiver, Sender};
use nalgebra::Isometry3;
use rayon::ThreadPool;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

type Moves = Vec<(ObjectId, Isometry3<f64>)>;

enum Command<C> {
    Frame(Detail),
    Add(ObjectDesc<C>, Sender<Result<ObjectId, PipelineError>>),
    Remove(ObjectId, Sender<Result<(), PipelineError>>),
}

/// A [`CollisionPipeline`] running on its own thread.
pub struct ConcurrentPipeline<C> {
    front: Arc<Mutex<Moves>>,
    commands: Sender<Command<C>>,
    reports: Receiver<FrameReport>,
    worker: JoinHandle<CollisionPipeline<C>>,
}

impl<C: ExactTest + 'static> ConcurrentPipeline<C> {
    /// Moves `pipeline` onto a new thread; its parallel stages use `pool` if given, else rayon's
    /// global pool. Fails only if the system cannot start a thread.
    pub fn spawn(
        pipeline: CollisionPipeline<C>,
        pool: Option<Arc<ThreadPool>>,
    ) -> std::io::Result<Self> {
        let front = Arc::new(Mutex::new(Moves::new()));
        let (commands, command_receiver) = crossbeam_channel::unbounded();
        let (report_sender, reports) = crossbeam_channel::unbounded();
        let worker_front = Arc::clone(&front);
        let worker = std::thread::Builder::new()
            .name("collision-pipeline".into())
            .spawn(move || {
                let serve = || serve(pipeline, &worker_front, &command_receiver, &report_sender);
                // The whole loop runs inside the pool, so the thread that runs the frames is one
                // of the pool's own: a frame starts without a hand-over to the pool, and the
                // first queued move can wake the pool's other threads (see `PoolWarmer`).
                match pool {
                    Some(pool) => pool.install(serve),
                    None => serve(),
                }
            })?;
        Ok(ConcurrentPipeline {
            front,
            commands,
            reports,
            worker,
        })
    }

    /// Queues a move for the next frame (a later move of the same object in the same frame wins).
    /// Moves of objects that are gone by then are dropped and counted in
    /// [`super::FrameStats::rejected_moves`].
    pub fn queue_move(&self, id: ObjectId, pose: Isometry3<f64>) -> Result<(), PipelineError> {
        check_pose(&pose, || format!("{id:?}"))?;
        lock(&self.front).push((id, pose));
        Ok(())
    }

    /// Asks for a frame over the moves queued so far; its report comes from
    /// [`ConcurrentPipeline::receive_report`].
    pub fn request_frame(&self, detail: Detail) -> Result<(), PipelineError> {
        self.commands
            .send(Command::Frame(detail))
            .map_err(|_| PipelineError::Closed)
    }

    /// Waits for the report of the oldest requested frame not yet received.
    pub fn receive_report(&self) -> Result<FrameReport, PipelineError> {
        self.reports.recv().map_err(|_| PipelineError::Closed)
    }

    /// The report of the oldest requested frame, if it is ready.
    pub fn try_receive_report(&self) -> Option<FrameReport> {
        self.reports.try_recv().ok()
    }

    /// Adds an object (between frames) and waits for its id.
    pub fn add(&self, desc: ObjectDesc<C>) -> Result<ObjectId, PipelineError> {
        let (reply, answer) = crossbeam_channel::bounded(1);
        self.commands
            .send(Command::Add(desc, reply))
            .map_err(|_| PipelineError::Closed)?;
        answer.recv().map_err(|_| PipelineError::Closed)?
    }

    /// Removes an object (between frames).
    pub fn remove(&self, id: ObjectId) -> Result<(), PipelineError> {
        let (reply, answer) = crossbeam_channel::bounded(1);
        self.commands
            .send(Command::Remove(id, reply))
            .map_err(|_| PipelineError::Closed)?;
        answer.recv().map_err(|_| PipelineError::Closed)?
    }

    /// Stops the thread after the frames already requested and returns the pipeline.
    ///
    /// # Panics
    /// Re-raises a panic of the pipeline thread.
    pub fn shutdown(self) -> CollisionPipeline<C> {
        drop(self.commands);
        self.worker
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    }
}

/// The pipeline thread: serves commands until the caller hangs up.
fn serve<C: ExactTest>(
    mut pipeline: CollisionPipeline<C>,
    front: &Mutex<Moves>,
    commands: &Receiver<Command<C>>,
    reports: &Sender<FrameReport>,
) -> CollisionPipeline<C> {
    let mut back = Moves::new();
    for command in commands {
        match command {
            Command::Frame(detail) => {
                std::mem::swap(&mut *lock(front), &mut back);
                let mut rejected = 0;
                for (id, pose) in back.drain(..) {
                    if pipeline.queue_move(id, pose).is_err() {
                        rejected += 1;
                    }
                }
                let mut report = pipeline.run_frame(detail);
                report.stats.rejected_moves = rejected;
                if reports.send(report).is_err() {
                    break;
                }
            }
            Command::Add(desc, reply) => {
                // The caller may have stopped waiting; nothing to do about it.
                let _ = reply.send(pipeline.add(desc));
            }
            Command::Remove(id, reply) => {
                let _ = reply.send(pipeline.remove(id));
            }
        }
    }
    pipeline
}
