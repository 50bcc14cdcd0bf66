//! Running sweeps on a cluster (Slurm): the sweep directory with the self-contained job specs
//! and the tasks' result records (`record`), the sbatch array scripts and the Slurm commands
//! (`slurm`), and the collection of finished results into the database (`collect`).
//!
//! Data flow: `sweep submit` registers the jobs in the database, writes their specs and an array
//! script into the sweep directory and submits it; each array task runs `wetgran job run SPEC
//! --out RESULT` (the same `run_job` as the local workers) and never opens the database, so no
//! SQLite lock ever crosses a network filesystem; `sweep collect` reads the result files back.

pub mod collect;
pub mod record;
pub mod slurm;

pub use collect::{Collected, QueueStates, collect, jobs_to_submit, queue_states};
pub use record::{Outcome, ResultRecord, SweepDir};
