//! What the synthetic person wears: the cloth of the shirt and the trousers (stripes, checks,
//! plain, a print, or the colours of the background), how loose it is, and the skin and hair.

use image::RgbImage;
use rand::{Rng, SeedableRng};

/// The surface a body primitive wears.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Material {
    Shirt,
    Trousers,
    Skin,
}

/// A cloth's pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pattern {
    /// Bands around the limb or trunk.
    Stripes,
    /// A checkerboard over the surface.
    Checks,
    /// One colour with a faint weave.
    Plain,
    /// Blotches of two colours (a printed fabric).
    Print,
}

/// One cloth: a pattern in two colours (RGB, 0–255).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cloth {
    /// The pattern.
    pub pattern: Pattern,
    /// First colour.
    pub a: [f64; 3],
    /// Second colour.
    pub b: [f64; 3],
}

/// How the person looks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Appearance {
    /// The shirt (trunk, shoulders, upper arms).
    pub shirt: Cloth,
    /// The trousers (hips and legs).
    pub trousers: Cloth,
    /// Skin (forearms, neck).
    pub skin: [f64; 3],
    /// The face, a little lighter than the forearms.
    pub face: [f64; 3],
    /// Hair.
    pub hair: [f64; 3],
    /// Radius factor of clothed parts (1 = fitted, 1.3 = loose).
    pub looseness: f64,
    /// Sleeves to the wrists (else to the elbows), on the mesh body.
    pub long_sleeves: bool,
    /// Shorts (else trousers to the ankles), on the mesh body.
    pub shorts: bool,
}

impl Default for Appearance {
    /// Red and white stripes over blue checked trousers, fitted: strong texture to track.
    fn default() -> Self {
        Appearance {
            shirt: Cloth {
                pattern: Pattern::Stripes,
                a: [200.0, 45.0, 40.0],
                b: [230.0, 225.0, 210.0],
            },
            trousers: Cloth {
                pattern: Pattern::Checks,
                a: [40.0, 60.0, 120.0],
                b: [70.0, 90.0, 160.0],
            },
            skin: [214.0, 160.0, 128.0],
            face: [224.0, 172.0, 140.0],
            hair: [60.0, 42.0, 30.0],
            looseness: 1.0,
            long_sleeves: false,
            shorts: false,
        }
    }
}

/// The kinds of clothes the benchmark suite draws from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clothes {
    /// Striped shirt, plain trousers.
    Stripes,
    /// Plain shirt and trousers.
    Plain,
    /// Checked shirt, plain trousers.
    Checks,
    /// Printed shirt and trousers.
    Print,
    /// Clothes in the background's own colours.
    Camouflage,
}

impl Clothes {
    /// Parses `stripes`, `plain`, `checks`, `print` or `camouflage`.
    pub fn from_name(name: &str) -> Option<Clothes> {
        match name {
            "stripes" => Some(Clothes::Stripes),
            "plain" => Some(Clothes::Plain),
            "checks" => Some(Clothes::Checks),
            "print" => Some(Clothes::Print),
            "camouflage" => Some(Clothes::Camouflage),
            _ => None,
        }
    }
}

impl Appearance {
    /// An appearance drawn from `seed`: colours at random (camouflage: the background's mean
    /// colour and a shade of it), skin and hair from a few tones, `loose` clothes 1.3 times as
    /// wide.
    pub fn drawn(clothes: Clothes, loose: bool, background: &RgbImage, seed: u64) -> Appearance {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed ^ 0x00C1_07E5);
        let colour = |rng: &mut rand::rngs::StdRng| -> [f64; 3] {
            [
                rng.random_range(20.0..235.0),
                rng.random_range(20.0..235.0),
                rng.random_range(20.0..235.0),
            ]
        };
        let mean = mean_colour(background);
        let shade = |c: [f64; 3], k: f64| c.map(|v| (v * k).clamp(0.0, 255.0));
        let cloth = |pattern, rng: &mut rand::rngs::StdRng| Cloth {
            pattern,
            a: colour(rng),
            b: colour(rng),
        };
        let (shirt, trousers) = match clothes {
            Clothes::Stripes => (
                cloth(Pattern::Stripes, &mut rng),
                cloth(Pattern::Plain, &mut rng),
            ),
            Clothes::Plain => (
                cloth(Pattern::Plain, &mut rng),
                cloth(Pattern::Plain, &mut rng),
            ),
            Clothes::Checks => (
                cloth(Pattern::Checks, &mut rng),
                cloth(Pattern::Plain, &mut rng),
            ),
            Clothes::Print => (
                cloth(Pattern::Print, &mut rng),
                cloth(Pattern::Print, &mut rng),
            ),
            Clothes::Camouflage => (
                Cloth {
                    pattern: Pattern::Print,
                    a: shade(mean, 0.95),
                    b: shade(mean, 1.1),
                },
                Cloth {
                    pattern: Pattern::Plain,
                    a: shade(mean, 0.85),
                    b: shade(mean, 0.9),
                },
            ),
        };
        const SKIN: [[f64; 3]; 4] = [
            [214.0, 160.0, 128.0],
            [236.0, 196.0, 170.0],
            [160.0, 110.0, 80.0],
            [100.0, 66.0, 48.0],
        ];
        const HAIR: [[f64; 3]; 4] = [
            [60.0, 42.0, 30.0],
            [20.0, 18.0, 16.0],
            [170.0, 130.0, 80.0],
            [120.0, 120.0, 120.0],
        ];
        let skin = SKIN[rng.random_range(0..SKIN.len())];
        Appearance {
            shirt,
            trousers,
            skin,
            face: skin.map(|c| (c * 1.05).min(255.0)),
            hair: HAIR[rng.random_range(0..HAIR.len())],
            looseness: if loose { 1.3 } else { 1.0 },
            long_sleeves: rng.random_bool(0.5),
            shorts: rng.random_bool(0.3),
        }
    }

    /// The colour of `material` at `along_m` metres along a part and `angle` around it.
    pub(crate) fn colour(&self, m: Material, along_m: f64, angle: f64, seed: f64) -> [f64; 3] {
        let n = value_noise(along_m * 30.0 + seed, angle * 3.0, 7);
        let cloth = match m {
            Material::Shirt => self.shirt,
            Material::Trousers => self.trousers,
            Material::Skin => return self.skin.map(|c| c * (0.9 + 0.1 * n)),
        };
        let (base, weave) = match cloth.pattern {
            Pattern::Stripes => {
                let stripe = (along_m * 18.0 + seed).sin() > 0.0;
                (if stripe { cloth.a } else { cloth.b }, 0.2)
            }
            Pattern::Checks => {
                let check = ((angle * 3.0).floor() as i64 + (along_m * 12.0).floor() as i64) & 1;
                (if check == 1 { cloth.b } else { cloth.a }, 0.25)
            }
            Pattern::Plain => (cloth.a, 0.1),
            Pattern::Print => {
                let blot = value_noise(along_m * 14.0 + seed * 3.0, angle * 2.0, 11);
                (if blot > 0.55 { cloth.b } else { cloth.a }, 0.15)
            }
        };
        base.map(|c| c * (1.0 - weave + weave * n))
    }
}

/// The mean colour of an image.
fn mean_colour(image: &RgbImage) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for p in image.pixels() {
        for (s, v) in sum.iter_mut().zip(p.0) {
            *s += f64::from(v);
        }
    }
    let n = (image.width() as f64 * image.height() as f64).max(1.0);
    sum.map(|s| s / n)
}

/// Cheap deterministic value noise in [0, 1] on a 2D lattice (for textures).
pub(crate) fn hash2(x: i64, y: i64, seed: u64) -> f64 {
    let mut h = (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ seed.wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^= h >> 29;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 32;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// Smooth value noise in [0, 1].
pub(crate) fn value_noise(x: f64, y: f64, seed: u64) -> f64 {
    let (xi, yi) = (x.floor() as i64, y.floor() as i64);
    let (fx, fy) = (x - x.floor(), y - y.floor());
    let s = |t: f64| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (s(fx), s(fy));
    let a = hash2(xi, yi, seed);
    let b = hash2(xi + 1, yi, seed);
    let c = hash2(xi, yi + 1, seed);
    let d = hash2(xi + 1, yi + 1, seed);
    let top = a + (b - a) * sx;
    let bottom = c + (d - c) * sx;
    top + (bottom - top) * sy
}
