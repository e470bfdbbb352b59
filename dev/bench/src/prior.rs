//! `videomocap-bench prior`: learns the lift's pose prior ([`videomocap_core::lift::learn`])
//! from a folder of motion-capture takes and writes its parameter file. Each take is mapped
//! onto the 16 joints by the core's BVH rig tables and resampled to `--per-second` poses per
//! second; a take of the suite's test split (or the salsa partner of one) is refused.

use crate::args::{GlobalArgs, PriorArgs};
use crate::{ExitError, say};
use anyhow::{Context, anyhow};
use std::io::Read;
use std::path::{Path, PathBuf};
use videomocap_core::bvh::{Bvh, map_to_model};
use videomocap_core::lift::{PosePrior, learn};
use videomocap_testkit::eval::suite::{Split, Suite};

/// The credit and terms the file carries (the CMU database's own words).
const SOURCE: &str = "Learned by `videomocap-bench prior` from CMU Graphics Lab Motion Capture Database takes (mocap.cs.cmu.edu, \"free for all uses\"): The data used in this project was obtained from mocap.cs.cmu.edu. The database was created with funding from NSF EIA-0196217.";

/// The take a file holds, in the suite's spelling (`iclone_003_01.bvh.gz` → `03_01`,
/// `61_12_scaled.bvh.gz` → `61_12`).
fn take_of(path: &Path) -> Option<String> {
    let name = path.file_name()?.to_str()?;
    let stem = name.strip_prefix("iclone_").unwrap_or(name);
    let mut parts = stem.split(['_', '.']);
    let subject: u32 = parts.next()?.parse().ok()?;
    let trial: u32 = parts.next()?.parse().ok()?;
    Some(format!("{subject:02}_{trial:02}"))
}

/// The salsa partner's take (subjects 60 and 61 dance together, trial by trial).
fn partner(take: &str) -> Option<String> {
    let (subject, trial) = take.split_once('_')?;
    match subject {
        "60" => Some(format!("61_{trial}")),
        "61" => Some(format!("60_{trial}")),
        _ => None,
    }
}

fn takes_in(dir: &Path, out: &mut Vec<PathBuf>) -> anyhow::Result<()> {
    for entry in std::fs::read_dir(dir).with_context(|| format!("{}", dir.display()))? {
        let path = entry?.path();
        if path.is_dir() {
            takes_in(&path, out)?;
        } else if path
            .file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| n.ends_with(".bvh") || n.ends_with(".bvh.gz"))
        {
            out.push(path);
        }
    }
    Ok(())
}

fn read_bvh(path: &Path) -> anyhow::Result<Bvh> {
    let bytes = std::fs::read(path).with_context(|| format!("{}", path.display()))?;
    let text = if path.extension().is_some_and(|e| e == "gz") {
        let mut s = String::new();
        flate2::read::GzDecoder::new(&bytes[..])
            .read_to_string(&mut s)
            .with_context(|| format!("{}: not gzip-compressed text", path.display()))?;
        s
    } else {
        String::from_utf8(bytes).with_context(|| format!("{}: not text", path.display()))?
    };
    Ok(Bvh::parse(&text, path)?)
}

/// Learns the prior and writes it.
pub(crate) fn run(a: &PriorArgs, global: &GlobalArgs) -> Result<(), ExitError> {
    let suite = Suite::load(&videomocap_testkit::repo_root()).map_err(ExitError::failed)?;
    let test: Vec<String> = suite
        .clips
        .iter()
        .filter(|c| c.split == Split::Test)
        .map(|c| c.take.clone())
        .collect();
    let mut files = Vec::new();
    takes_in(&a.mocap, &mut files).map_err(ExitError::bad_input)?;
    files.sort();
    if files.is_empty() {
        return Err(ExitError::bad_input(anyhow!(
            "{}: no .bvh or .bvh.gz takes",
            a.mocap.display()
        )));
    }
    let mut poses = Vec::new();
    let mut used = Vec::new();
    for path in &files {
        let take = take_of(path).unwrap_or_default();
        if test.contains(&take) || partner(&take).is_some_and(|p| test.contains(&p)) {
            return Err(ExitError::bad_input(anyhow!(
                "{}: take {take} is in the suite's test split (or dances with one): never learn from it",
                path.display()
            )));
        }
        let bvh = read_bvh(path).map_err(ExitError::bad_input)?;
        let motion = map_to_model(&bvh, path).map_err(ExitError::bad_input)?;
        // Frame 0 of the iClone takes is a T-pose, not motion.
        let step = (motion.fps / a.per_second).round().max(1.0) as usize;
        let before = poses.len();
        poses.extend(motion.frames.iter().skip(1).step_by(step).copied());
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        say(global, &format!("{name}: {} poses", poses.len() - before));
        used.push(name);
    }
    let file = learn(&poses, a.components, used, SOURCE.to_owned())
        .map_err(|e| ExitError::failed(anyhow!(e)))?;
    let text = serde_json::to_string(&file).map_err(ExitError::failed)?;
    // What is written must read back.
    PosePrior::parse(&text, &a.out).map_err(ExitError::failed)?;
    std::fs::write(&a.out, text + "\n")
        .with_context(|| format!("{}", a.out.display()))
        .map_err(ExitError::failed)?;
    let unusual: Vec<String> = file
        .groups
        .iter()
        .map(|g| format!("{} {:.1}", g.name, g.unusual))
        .collect();
    println!(
        "{} poses from {} takes, {} components per group, unusual beyond (nats) {}: {}",
        poses.len(),
        file.takes.len(),
        a.components,
        unusual.join(", "),
        a.out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn takes_are_read_in_the_suites_spelling() {
        assert_eq!(
            take_of(Path::new("x/iclone_003_01.bvh.gz")).as_deref(),
            Some("03_01")
        );
        assert_eq!(
            take_of(Path::new("61_12_scaled.bvh.gz")).as_deref(),
            Some("61_12")
        );
        assert_eq!(partner("60_12").as_deref(), Some("61_12"));
        assert_eq!(partner("05_12"), None);
    }
}
