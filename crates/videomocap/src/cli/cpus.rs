//! How many threads a command may run on: `--threads` when given, else the CPUs this process
//! may use (its CPU affinity mask and cgroup quota, as the OS reports them), never more than
//! a Slurm task was given (`SLURM_CPUS_PER_TASK`, set by `sbatch --cpus-per-task`). On a
//! cluster that does not pin tasks to cores, the mask holds every core of the node, and only
//! Slurm's variable says that a `-c 1` task owns one of them.
//!
//! The one number reaches every pool a run starts: the tracker's rayon pool, the pose
//! network's (tract) pool, FFmpeg's decoder threads and rayon's global pool.

use super::ExitError;
use anyhow::anyhow;

/// Slurm's CPUs for each task of the job (`--cpus-per-task`).
pub(crate) const SLURM_CPUS_PER_TASK: &str = "SLURM_CPUS_PER_TASK";

/// Where a command's thread count came from, for its report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ThreadSource {
    /// `--threads N`.
    Requested,
    /// `SLURM_CPUS_PER_TASK`, smaller than the affinity mask.
    Slurm,
    /// The CPUs the process may run on (affinity mask, cgroup quota).
    Affinity,
}

/// The thread count a command may use, and why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ThreadBudget {
    /// Threads (at least 1).
    pub threads: usize,
    /// Where the number came from.
    pub source: ThreadSource,
}

/// The budget of this process: `requested` (`--threads`), else the affinity mask capped by
/// `SLURM_CPUS_PER_TASK`. `--threads 0` is bad input.
pub(crate) fn thread_budget(requested: Option<usize>) -> Result<ThreadBudget, ExitError> {
    let affinity = std::thread::available_parallelism().map_or(1, |n| n.get());
    let slurm = std::env::var(SLURM_CPUS_PER_TASK).ok();
    budget_from(requested, affinity, slurm.as_deref())
}

/// [`thread_budget`] from its inputs (a malformed Slurm variable is ignored with a warning).
fn budget_from(
    requested: Option<usize>,
    affinity: usize,
    slurm: Option<&str>,
) -> Result<ThreadBudget, ExitError> {
    if let Some(n) = requested {
        if n == 0 {
            return Err(ExitError::bad_input(anyhow!(
                "--threads must be at least 1"
            )));
        }
        return Ok(ThreadBudget {
            threads: n,
            source: ThreadSource::Requested,
        });
    }
    let affinity = affinity.max(1);
    let slurm = slurm.and_then(|text| match text.trim().parse::<usize>() {
        Ok(n) if n > 0 => Some(n),
        _ => {
            eprintln!("warning: {SLURM_CPUS_PER_TASK}={text:?} is not a CPU count; ignored");
            None
        }
    });
    Ok(match slurm {
        Some(n) if n < affinity => ThreadBudget {
            threads: n,
            source: ThreadSource::Slurm,
        },
        _ => ThreadBudget {
            threads: affinity,
            source: ThreadSource::Affinity,
        },
    })
}

/// Sizes rayon's global pool to `threads` (work that runs outside a pool of its own), once per
/// process; later calls keep the first size.
pub(crate) fn limit_global_pool(threads: usize) {
    // An error means the pool exists already (a second command in one process, i.e. tests).
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .thread_name(|k| format!("videomocap-global-{k}"))
        .build_global();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slurm_cpus_per_task_caps_the_affinity_mask_and_threads_overrides_both() {
        let b = |req, aff, slurm| budget_from(req, aff, slurm).expect("budget");
        // A `-c 1` task on a 2-core node that does not pin: one thread.
        assert_eq!(b(None, 2, Some("1")).threads, 1);
        assert_eq!(b(None, 2, Some("1")).source, ThreadSource::Slurm);
        // A mask smaller than Slurm's number wins (pinned to 2 of 4 cores).
        assert_eq!(b(None, 2, Some("4")).threads, 2);
        assert_eq!(b(None, 2, Some("4")).source, ThreadSource::Affinity);
        // Outside Slurm, or with a malformed variable: the mask.
        assert_eq!(b(None, 8, None).threads, 8);
        assert_eq!(b(None, 8, Some("two")).threads, 8);
        assert_eq!(b(None, 8, Some("0")).threads, 8);
        // The user's number is kept as given.
        assert_eq!(b(Some(3), 2, Some("1")).threads, 3);
        assert!(budget_from(Some(0), 2, None).is_err());
    }
}
