use videomocap::skeleton::{Joint, SubjectModel};
use videomocap::synth::*;
use videomocap::volume::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let kind = ProceduralMotion::from_name(&args[1]).unwrap();
    let v: f64 = args[2].parse().unwrap();
    let m = procedural(kind, &SubjectModel::default(), 50, 15.0);
    let st = stature_of(&m);
    let mut rng = <rand::rngs::StdRng as rand::SeedableRng>::seed_from_u64(1);
    let mut p = VolumeParams::default();
    if let Ok(r) = std::env::var("VM_R") {
        p.radius_spacings = r.parse().unwrap();
    }
    if let Ok(r) = std::env::var("VM_L") {
        p.landmarks = r.parse().unwrap();
    }
    if args.len() > 4 {
        let mut r2 = <rand::rngs::StdRng as rand::SeedableRng>::seed_from_u64(1);
        tree_dump(&voxelise(
            &m.frames[0],
            st,
            &VoxelParams {
                voxel_m: v,
                ..Default::default()
            },
            &mut r2,
        ));
        return;
    }
    let res: Vec<_> = m
        .frames
        .iter()
        .map(|j| {
            process_frame(
                &voxelise(
                    j,
                    st,
                    &VoxelParams {
                        voxel_m: v,
                        ..Default::default()
                    },
                    &mut rng,
                ),
                &p,
            )
        })
        .collect();
    let names: Vec<String> = (0..50).map(|i| i.to_string()).collect();
    for (i, r) in res.iter().enumerate() {
        if let Err(e) = r {
            if i < 3 {
                println!("frame {i}: {e}");
            }
        }
    }
    let a = assemble(&res, &names, 15.0);
    let t = volume_truth(&m);
    let mut sum = [0.0; 16];
    let mut n = 0;
    for f in &a.skeleton.frames {
        let g = &t.frames[f.index].points;
        for j in Joint::ALL {
            sum[j.index()] += (f.points[j] - g[j]).norm();
        }
        n += 1;
    }
    for j in Joint::ALL {
        println!(
            "{:<16} {:6.1}",
            j.name(),
            1000.0 * sum[j.index()] / n as f64
        );
    }
    println!(
        "sides {:?} art {:?} warnings {}",
        a.sides_from,
        a.articulated,
        a.warnings.len()
    );
    if let Some(fr) = args.get(3) {
        let i: usize = fr.parse().unwrap();
        if let Ok(r) = &res[i] {
            dump(&r.curve);
        }
        let f = &a.skeleton.frames[i];
        let g = &t.frames[f.index].points;
        for j in Joint::ALL {
            println!(
                "{:<16} got {:7.3} {:7.3} {:7.3}  true {:7.3} {:7.3} {:7.3}",
                j.name(),
                f.points[j].x,
                f.points[j].y,
                f.points[j].z,
                g[j].x,
                g[j].y,
                g[j].z
            );
        }
    }
}
#[allow(dead_code)]
fn dump(c: &SkeletonCurve) {
    let show = |name: &str, chain: &Vec<usize>| {
        let a = c.parents[chain[0]].unwrap_or(c.root);
        let pts: Vec<String> = chain
            .iter()
            .map(|&k| {
                format!(
                    "({:.2},{:.2},{:.2})",
                    c.points[k].x, c.points[k].y, c.points[k].z
                )
            })
            .collect();
        println!(
            "{name}: attach {} {:?} n{} -> {}",
            a,
            c.points[a],
            chain.len(),
            pts.join(" ")
        );
    };
    println!("root {} chest {} pelvis {}", c.root, c.chest, c.pelvis);
    show("head", &c.head);
    show("arm1", &c.arms[0]);
    show("arm2", &c.arms[1]);
    show("leg1", &c.legs[0]);
    show("leg2", &c.legs[1]);
}
#[allow(dead_code)]
pub fn tree_dump(pts: &[nalgebra::Point3<f64>]) {
    use videomocap::volume::{isomap, shells};
    let sp = point_spacing(pts);
    let e = isomap::embed(
        pts,
        &IsomapParams {
            neighbourhood: Neighbourhood::Radius(sp * 1.8),
            landmarks: 12,
        },
    )
    .unwrap();
    let t = shells::build(&e.coords, &ShellParams::default());
    fn rec(
        t: &shells::ShellTree,
        k: usize,
        ind: usize,
        e: &isomap::Embedding,
        pts: &[nalgebra::Point3<f64>],
    ) {
        let n = &t.nodes[k];
        let c = n
            .members
            .iter()
            .map(|&i| pts[e.kept[i]].coords)
            .sum::<nalgebra::Vector3<f64>>()
            / n.members.len() as f64;
        println!(
            "{}{} s{} m{} ({:.2},{:.2},{:.2})",
            " ".repeat(ind),
            k,
            n.shell,
            n.members.len(),
            c.x,
            c.y,
            c.z
        );
        for &ch in &n.children {
            rec(
                t,
                ch,
                ind + if n.children.len() > 1 { 2 } else { 0 },
                e,
                pts,
            );
        }
    }
    rec(&t, t.root, 0, &e, pts);
}
