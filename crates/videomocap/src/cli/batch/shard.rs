//! Which rows one process of a sharded batch runs: `--shard K/N`, or `--shard slurm` for K and
//! N from the Slurm job array the process runs in.
//!
//! Rows are dealt like cards in manifest order: row i (0-based, counting every row) goes to
//! shard i mod N. Each shard gets ⌊R/N⌋ or ⌈R/N⌉ of R rows, the fewest a slowest task can
//! have, and rows appended to the manifest never move the rows above them, so a grown manifest
//! run with the same N sends every earlier row to the shard it had. Hashing the id (the
//! earlier rule, and rendezvous hashing alike) keeps a row's shard whatever else changes, but
//! with few rows it is very uneven (6 rows over 3 shards came out 0 / 4 / 2, doubling the
//! array's time); consistent hashing with bounded loads evens the loads but moves earlier rows
//! when rows are added. Inserting or reordering rows does move rows between shards; a row
//! already done is skipped whichever shard reads it.

use crate::cli::ExitError;
use anyhow::anyhow;

/// One shard of N.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Shard {
    /// This shard, 0 to `count` − 1.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

impl Shard {
    /// Whether the row at `position` (0-based, in manifest order) belongs to this shard.
    pub(super) fn holds(&self, position: usize) -> bool {
        position % self.count == self.index
    }
}

/// Reads `--shard K/N` or `--shard slurm` (from the process's environment).
pub(super) fn parse_shard(text: &str) -> Result<Shard, ExitError> {
    if text.trim().eq_ignore_ascii_case("slurm") {
        return from_slurm(|name| std::env::var(name).ok())
            .map_err(|e| ExitError::bad_input(anyhow!("--shard slurm: {e}")));
    }
    let bad = || {
        ExitError::bad_input(anyhow!(
            "--shard {text}: expected K/N with 0 ≤ K < N, or slurm"
        ))
    };
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let (index, count): (usize, usize) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if index >= count {
        return Err(bad());
    }
    Ok(Shard { index, count })
}

/// The shard of a Slurm job-array task: K = (SLURM_ARRAY_TASK_ID − MIN) / STEP and N = the
/// array's task count (SLURM_ARRAY_TASK_COUNT, or from MIN, MAX and STEP when it is absent).
/// An array whose ids are not evenly spaced (`--array=1,4,9`) is refused: its K would not
/// be 0 to N − 1.
fn from_slurm(var: impl Fn(&str) -> Option<String>) -> Result<Shard, String> {
    let number = |name: &str| -> Result<Option<usize>, String> {
        var(name)
            .map(|v| {
                v.trim()
                    .parse::<usize>()
                    .map_err(|_| format!("{name}={v:?} is not a number"))
            })
            .transpose()
    };
    let Some(id) = number("SLURM_ARRAY_TASK_ID")? else {
        return Err(
            "SLURM_ARRAY_TASK_ID is not set: this is not a task of a Slurm job \
                    array (sbatch --array=0-N); give --shard K/N instead"
                .into(),
        );
    };
    let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
    let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
    let max = number("SLURM_ARRAY_TASK_MAX")?;
    let spaced = max.map(|max| max.saturating_sub(min) / step + 1);
    let count = match (number("SLURM_ARRAY_TASK_COUNT")?, spaced) {
        (Some(c), Some(s)) if c != s => {
            return Err(format!(
                "the array's task ids are not evenly spaced ({c} tasks from {min} to {}); \
                 use --array=0-{} (or --shard K/N)",
                max.unwrap_or(min),
                c.saturating_sub(1)
            ));
        }
        (Some(c), _) => c,
        (None, Some(s)) => s,
        (None, None) => {
            return Err("neither SLURM_ARRAY_TASK_COUNT nor SLURM_ARRAY_TASK_MAX is set".into());
        }
    };
    let offset = id
        .checked_sub(min)
        .filter(|o| o % step == 0)
        .ok_or_else(|| format!("task {id} is not one of the array's task ids"))?;
    let index = offset / step;
    if index >= count {
        return Err(format!("task {id} is past the array's {count} tasks"));
    }
    Ok(Shard { index, count })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn slurm(vars: &[(&str, &str)]) -> Result<Shard, String> {
        let map: BTreeMap<String, String> = vars
            .iter()
            .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
            .collect();
        from_slurm(|name| map.get(name).cloned())
    }

    #[test]
    fn dealing_rows_gives_every_shard_its_even_share_and_appending_moves_none() {
        let loads = |rows: usize, n: usize| -> Vec<usize> {
            (0..n)
                .map(|k| {
                    let shard = Shard { index: k, count: n };
                    (0..rows).filter(|&i| shard.holds(i)).count()
                })
                .collect()
        };
        // The case: 6 rows over 3 shards (hashing gave 0 / 4 / 2).
        assert_eq!(loads(6, 3), vec![2, 2, 2]);
        assert_eq!(loads(7, 3), vec![3, 2, 2]);
        assert_eq!(loads(2, 4), vec![1, 1, 0, 0]);
        // Every row in exactly one shard.
        for i in 0..50 {
            let owners = (0..7)
                .filter(|&k| Shard { index: k, count: 7 }.holds(i))
                .count();
            assert_eq!(owners, 1);
        }
        // A row's shard depends on its position only: rows appended after it leave it be.
        let owner = |i: usize| (0..5).find(|&k| Shard { index: k, count: 5 }.holds(i));
        let before: Vec<_> = (0..6).map(owner).collect();
        let after: Vec<_> = (0..40).map(owner).collect();
        assert_eq!(before[..], after[..6]);
    }

    #[test]
    fn shard_k_of_n_is_read_and_bad_ones_are_refused() {
        assert_eq!(parse_shard("2/3").ok(), Some(Shard { index: 2, count: 3 }));
        assert!(parse_shard("3/3").is_err());
        assert!(parse_shard("x").is_err());
        assert!(parse_shard("1/0").is_err());
    }

    #[test]
    fn the_slurm_array_gives_k_and_n() {
        let s = |k: usize, n: usize| -> Result<Shard, String> { Ok(Shard { index: k, count: n }) };
        // --array=0-99, task 7.
        let base = [
            ("SLURM_ARRAY_TASK_ID", "7"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_MAX", "99"),
        ];
        assert_eq!(
            slurm(&[base[0], base[1], base[2], ("SLURM_ARRAY_TASK_COUNT", "100")]),
            s(7, 100)
        );
        // Older Slurm without COUNT: from MIN and MAX.
        assert_eq!(slurm(&base), s(7, 100));
        // --array=1-10: task 1 is shard 0 of 10.
        assert_eq!(
            slurm(&[
                ("SLURM_ARRAY_TASK_ID", "1"),
                ("SLURM_ARRAY_TASK_MIN", "1"),
                ("SLURM_ARRAY_TASK_MAX", "10"),
                ("SLURM_ARRAY_TASK_COUNT", "10"),
            ]),
            s(0, 10)
        );
        // --array=0-8:2 (0, 2, 4, 6, 8): task 6 is shard 3 of 5.
        assert_eq!(
            slurm(&[
                ("SLURM_ARRAY_TASK_ID", "6"),
                ("SLURM_ARRAY_TASK_MIN", "0"),
                ("SLURM_ARRAY_TASK_MAX", "8"),
                ("SLURM_ARRAY_TASK_STEP", "2"),
                ("SLURM_ARRAY_TASK_COUNT", "5"),
            ]),
            s(3, 5)
        );
        // --array=1,4,9: refused.
        let uneven = slurm(&[
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_MAX", "9"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ]);
        assert!(uneven.is_err_and(|e| e.contains("not evenly spaced")));
        // Not in an array at all.
        assert!(slurm(&[]).is_err_and(|e| e.contains("SLURM_ARRAY_TASK_ID is not set")));
        assert!(slurm(&[("SLURM_ARRAY_TASK_ID", "x")]).is_err());
    }
}
