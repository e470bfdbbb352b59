//! Per-frame point clouds: reading PLY (ASCII and binary, through `ply-rs-bw`), XYZ text and
//! voxel occupancy grids, listing a sequence directory, and writing binary PLY (for `synth`).

use super::VolumeError;
use super::voxel::VoxelGrid;
use nalgebra::Point3;
use ply_rs_bw::ply::{
    Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType,
    ScalarType,
};
use std::path::{Path, PathBuf};

/// The points of one frame, metres, in the volume's own frame (any right-handed frame).
pub type PointCloud = Vec<Point3<f64>>;

/// File kinds a volume sequence may contain, told apart by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CloudKind {
    /// `.ply`, ASCII or binary (either byte order); the `vertex` element's x, y, z.
    Ply,
    /// `.xyz` or `.txt`: one point per line, three numbers separated by spaces or commas;
    /// `#` starts a comment; further columns (colours, normals) are ignored.
    Xyz,
    /// `.voxels.json`: a `videomocap.voxels` occupancy grid (see `docs/formats.md`).
    Voxels,
}

impl CloudKind {
    /// The kind a file name says it is, if any.
    pub fn of(path: &Path) -> Option<CloudKind> {
        let name = path.file_name()?.to_str()?.to_ascii_lowercase();
        if name.ends_with(".voxels.json") {
            Some(CloudKind::Voxels)
        } else if name.ends_with(".ply") {
            Some(CloudKind::Ply)
        } else if name.ends_with(".xyz") || name.ends_with(".txt") {
            Some(CloudKind::Xyz)
        } else {
            None
        }
    }
}

/// The frame files of a sequence directory in natural order (`frame2` before `frame10`).
pub fn list_frames(dir: &Path) -> Result<Vec<PathBuf>, VolumeError> {
    let entries = std::fs::read_dir(dir).map_err(VolumeError::io(dir))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && CloudKind::of(p).is_some())
        .collect();
    files.sort_by(|a, b| natord::compare(&a.to_string_lossy(), &b.to_string_lossy()));
    if files.is_empty() {
        let problem = if dir.join("cameras.json").is_file() {
            "no point clouds here, but cameras.json: carve this set-up first \
             (videomocap carve DIR -o GRIDS), then open GRIDS"
        } else {
            "no point clouds here (expected .ply, .xyz, .txt or .voxels.json files)"
        };
        return Err(VolumeError::Invalid {
            path: dir.to_owned(),
            problem: problem.into(),
        });
    }
    Ok(files)
}

/// Reads one frame's points; non-finite points are an error naming the line or vertex.
pub fn read_cloud(path: &Path) -> Result<PointCloud, VolumeError> {
    let kind = CloudKind::of(path).ok_or_else(|| VolumeError::Invalid {
        path: path.to_owned(),
        problem: "unknown point cloud type (expected .ply, .xyz, .txt or .voxels.json)".into(),
    })?;
    let bytes = std::fs::read(path).map_err(VolumeError::io(path))?;
    parse_cloud(kind, &bytes, path)
}

/// Parses one frame's points from the bytes of a file of the given kind; `path` names the
/// file in errors. This is what [`read_cloud`] does after reading the file, and what the
/// fuzz targets call.
pub fn parse_cloud(kind: CloudKind, bytes: &[u8], path: &Path) -> Result<PointCloud, VolumeError> {
    let text = || {
        std::str::from_utf8(bytes).map_err(|e| VolumeError::Invalid {
            path: path.to_owned(),
            problem: format!("not UTF-8 text: {e}"),
        })
    };
    let points = match kind {
        CloudKind::Ply => parse_ply(bytes, path)?,
        CloudKind::Xyz => parse_xyz(text()?, path)?,
        CloudKind::Voxels => VoxelGrid::parse(text()?, path)?.centres(),
    };
    if let Some(i) = points
        .iter()
        .position(|p| !p.coords.iter().all(|c| c.is_finite()))
    {
        return Err(VolumeError::Invalid {
            path: path.to_owned(),
            problem: format!("point {i} has a coordinate that is not a finite number"),
        });
    }
    Ok(points)
}

fn parse_ply(bytes: &[u8], path: &Path) -> Result<PointCloud, VolumeError> {
    let mut reader = bytes;
    let parser = ply_rs_bw::parser::Parser::<DefaultElement>::new();
    let ply = parser
        .read_ply(&mut reader)
        .map_err(|e| VolumeError::Invalid {
            path: path.to_owned(),
            problem: format!("not a readable PLY file: {e}"),
        })?;
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or_else(|| VolumeError::Invalid {
            path: path.to_owned(),
            problem: "the PLY file has no \"vertex\" element".into(),
        })?;
    let number = |e: &DefaultElement, key: &str, i: usize| -> Result<f64, VolumeError> {
        let v = match e.get(key) {
            Some(Property::Float(v)) => f64::from(*v),
            Some(Property::Double(v)) => *v,
            Some(Property::Char(v)) => f64::from(*v),
            Some(Property::UChar(v)) => f64::from(*v),
            Some(Property::Short(v)) => f64::from(*v),
            Some(Property::UShort(v)) => f64::from(*v),
            Some(Property::Int(v)) => f64::from(*v),
            Some(Property::UInt(v)) => f64::from(*v),
            _ => {
                return Err(VolumeError::Invalid {
                    path: path.to_owned(),
                    problem: format!("vertex {i} has no numeric \"{key}\" property"),
                });
            }
        };
        Ok(v)
    };
    vertices
        .iter()
        .enumerate()
        .map(|(i, e)| {
            Ok(Point3::new(
                number(e, "x", i)?,
                number(e, "y", i)?,
                number(e, "z", i)?,
            ))
        })
        .collect()
}

fn parse_xyz(text: &str, path: &Path) -> Result<PointCloud, VolumeError> {
    let mut points = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let mut values = line
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .take(3)
            .map(str::parse::<f64>);
        let mut next = || match values.next() {
            Some(Ok(v)) => Ok(v),
            _ => Err(VolumeError::Invalid {
                path: path.to_owned(),
                problem: format!(
                    "line {}: expected three numbers x y z, got \"{line}\"",
                    n + 1
                ),
            }),
        };
        points.push(Point3::new(next()?, next()?, next()?));
    }
    Ok(points)
}

/// Writes points as a binary little-endian PLY with float x, y, z (what `synth --volume` makes).
pub fn write_ply(path: &Path, points: &[Point3<f64>]) -> Result<(), VolumeError> {
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    let mut vertex = ElementDef::new("vertex".to_owned());
    for key in ["x", "y", "z"] {
        vertex.properties.add(PropertyDef::new(
            key.to_owned(),
            PropertyType::Scalar(ScalarType::Float),
        ));
    }
    ply.header.elements.add(vertex);
    let rows = points
        .iter()
        .map(|p| {
            let mut e = DefaultElement::new();
            e.insert("x".to_owned(), Property::Float(p.x as f32));
            e.insert("y".to_owned(), Property::Float(p.y as f32));
            e.insert("z".to_owned(), Property::Float(p.z as f32));
            e
        })
        .collect();
    ply.payload.insert("vertex".to_owned(), rows);
    let mut bytes = Vec::new();
    ply_rs_bw::writer::Writer::new()
        .write_ply(&mut bytes, &mut ply)
        .map_err(VolumeError::io(path))?;
    Ok(videomocap_core::formats::write_atomically(path, &bytes)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binary_ply_round_trips_and_ascii_ply_and_xyz_read() {
        let dir = tempfile::tempdir().unwrap();
        let pts = vec![Point3::new(0.5, -1.0, 2.25), Point3::new(1.0, 2.0, 3.0)];
        let bin = dir.path().join("a.ply");
        write_ply(&bin, &pts).unwrap();
        assert_eq!(read_cloud(&bin).unwrap(), pts);

        let ascii = dir.path().join("b.ply");
        std::fs::write(
            &ascii,
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n\
             property double z\nproperty uchar red\nend_header\n0.5 -1 2.25 9\n1 2 3 9\n",
        )
        .unwrap();
        assert_eq!(read_cloud(&ascii).unwrap(), pts);

        let xyz = dir.path().join("c.xyz");
        std::fs::write(&xyz, "# x y z\n0.5 -1 2.25\n1,2,3, 255 0 0\n\n").unwrap();
        assert_eq!(read_cloud(&xyz).unwrap(), pts);
    }

    #[test]
    fn bad_files_name_the_file_and_the_problem() {
        let dir = tempfile::tempdir().unwrap();
        let xyz = dir.path().join("bad.xyz");
        std::fs::write(&xyz, "1 2 3\n1 2\n").unwrap();
        let e = read_cloud(&xyz).unwrap_err().to_string();
        assert!(e.contains("bad.xyz") && e.contains("line 2"), "{e}");
        std::fs::write(&xyz, "1 2 NaN\n").unwrap();
        let e = read_cloud(&xyz).unwrap_err().to_string();
        assert!(e.contains("not a finite number"), "{e}");
        let ply = dir.path().join("bad.ply");
        std::fs::write(
            &ply,
            "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n",
        )
        .unwrap();
        assert!(
            read_cloud(&ply)
                .unwrap_err()
                .to_string()
                .contains("bad.ply")
        );
        let empty = tempfile::tempdir().unwrap();
        let e = list_frames(empty.path()).unwrap_err().to_string();
        assert!(e.contains("no point clouds"), "{e}");
    }
}
