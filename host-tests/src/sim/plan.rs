//! Which orientations the sensor is held in ([`Plan`]) and the body-to-world rotation of every pose
//! (`glam` quaternions). The geometry is described in the [module documentation](super).

use std::f64::consts::FRAC_PI_2;
use std::fmt;
use std::str::FromStr;

use glam::{DQuat, DVec3};

use super::config::{DEFAULT_FLIP_DEG, DEFAULT_TILT_DEG};
use super::random::{Stream, random_rotation, stream_rng, uniform_in};

/// Which orientations the sensor is held in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Plan {
    /// The paper's 24 positions: faces `+z, +y, -z, +x, -x, -y` up (the paper's order), each turned
    /// four times by 90° about the vertical on a tilted platform, with a flip error per face.
    Paper24,
    /// 26 directions: 6 faces, 12 edges, 8 vertices of a cube, with the same tilt/flip model
    /// (one placement each, no turn).
    Cube26,
    /// `N >= 1` hand-placed orientations drawn uniformly on SO(3).
    Random(usize),
    /// A free-hand session: `N >= 1` orientations drawn uniformly on SO(3), held by hand for a few
    /// seconds each ([`SimConfig::for_plan`](super::SimConfig::for_plan): 4 s holds, 1.5 s rotations
    /// with the hand's shake, no long initial rest). No face is ever aligned.
    FreeHand(usize),
}

impl Plan {
    /// Number of poses.
    pub fn pose_count(&self) -> usize {
        match self {
            Self::Paper24 => 24,
            Self::Cube26 => 26,
            Self::Random(n) | Self::FreeHand(n) => *n,
        }
    }

    /// Default [`SimConfig::initial_rest_s`](super::SimConfig::initial_rest_s): 0 s on a platform,
    /// 10 s for hand-placed poses.
    pub fn default_initial_rest_s(&self) -> f64 {
        match self {
            Self::Paper24 | Self::Cube26 => 0.0,
            Self::Random(_) => 10.0,
            Self::FreeHand(_) => 0.0,
        }
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Paper24 => f.write_str("paper24"),
            Self::Cube26 => f.write_str("cube26"),
            Self::Random(n) => write!(f, "random:{n}"),
            Self::FreeHand(n) => write!(f, "freehand:{n}"),
        }
    }
}

/// Why a plan name did not parse.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ParsePlanError {
    /// Not `paper24`, `cube26`, `random:N` or `freehand:N`.
    UnknownPlan(String),
    /// `random:N` with `N` not a whole number `>= 1`.
    InvalidCount(String),
}

impl fmt::Display for ParsePlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UnknownPlan(s) => {
                write!(f, "unknown plan `{s}` (expected paper24, cube26, random:N or freehand:N)")
            }
            Self::InvalidCount(s) => {
                write!(f, "invalid pose count `{s}` in random:N (expected N >= 1)")
            }
        }
    }
}

impl std::error::Error for ParsePlanError {}

impl FromStr for Plan {
    type Err = ParsePlanError;

    /// Parses `paper24`, `cube26` or `random:N` (case-insensitive, surrounding spaces ignored).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let text = s.trim().to_ascii_lowercase();
        match text.as_str() {
            "paper24" => Ok(Self::Paper24),
            "cube26" => Ok(Self::Cube26),
            _ => {
                let (make, count): (fn(usize) -> Self, _) = if let Some(c) = text.strip_prefix("random:") {
                    (Self::Random, c)
                } else if let Some(c) = text.strip_prefix("freehand:") {
                    (Self::FreeHand, c)
                } else {
                    return Err(ParsePlanError::UnknownPlan(s.to_string()));
                };
                match count.trim().parse::<usize>() {
                    Ok(n) if n >= 1 => Ok(make(n)),
                    _ => Err(ParsePlanError::InvalidCount(count.to_string())),
                }
            }
        }
    }
}

/// Unit specific-force directions in the body frame (what `f_b / g` is at rest) for each pose, with
/// the default tilt (1.5°) and flip error (±2°). See [`plan_directions_with`].
pub fn plan_directions(plan: &Plan, seed: u64) -> Vec<[f64; 3]> {
    plan_directions_with(plan, seed, DEFAULT_TILT_DEG, DEFAULT_FLIP_DEG)
}

/// Unit specific-force directions in the body frame for each pose, with the given platform tilt and
/// flip-error bound in degrees (ignored by [`Plan::Random`]). Deterministic by `seed`; these are the
/// directions [`simulate`](super::simulate) uses for the same plan, seed, tilt and flip.
pub fn plan_directions_with(plan: &Plan, seed: u64, tilt_deg: f64, flip_deg: f64) -> Vec<[f64; 3]> {
    placement_rotations(plan, seed, tilt_deg, flip_deg).iter().map(|r| up_in_body(*r).to_array()).collect()
}

/// Body-to-world rotations `R_wb` of every pose (see the module documentation).
pub(crate) fn placement_rotations(plan: &Plan, seed: u64, tilt_deg: f64, flip_deg: f64) -> Vec<DQuat> {
    let mut rng = stream_rng(seed, Stream::Geometry);
    let tilt = DQuat::from_rotation_x(tilt_deg.to_radians());
    let flip_rad = flip_deg.to_radians();
    let mut place = |up: DVec3| {
        let alpha = uniform_in(&mut rng, -flip_rad, flip_rad);
        let beta = uniform_in(&mut rng, -flip_rad, flip_rad);
        DQuat::from_rotation_x(alpha) * DQuat::from_rotation_y(beta) * rotation_onto_up(up)
    };
    match plan {
        Plan::Paper24 => PAPER_FACES
            .iter()
            .flat_map(|&face| {
                let placed = place(DVec3::from_array(face));
                (0..4).map(move |turn| tilt * DQuat::from_rotation_z(f64::from(turn) * FRAC_PI_2) * placed)
            })
            .collect(),
        Plan::Cube26 => cube26_nominal().into_iter().map(|dir| tilt * place(DVec3::from_array(dir))).collect(),
        Plan::Random(n) | Plan::FreeHand(n) => (0..*n).map(|_| random_rotation(&mut rng)).collect(),
    }
}

/// The paper's faces in its order: `+z, +y, -z, +x, -x, -y` up.
const PAPER_FACES: [[f64; 3]; 6] =
    [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];

/// World up in body coordinates, `R_wbᵀ e_z`.
pub(crate) fn up_in_body(r_wb: DQuat) -> DVec3 {
    r_wb.inverse() * DVec3::Z
}

/// The shortest rotation taking the unit vector `from` onto `e_z` (180° about `x` for `-e_z`, where
/// the shortest one is not unique).
fn rotation_onto_up(from: DVec3) -> DQuat {
    if from.dot(DVec3::Z) < -1.0 + 1e-12 {
        DQuat::from_rotation_x(std::f64::consts::PI)
    } else {
        DQuat::from_rotation_arc(from, DVec3::Z)
    }
}

/// The 26 nominal cube directions: faces (paper order), then edges, then vertices; unit length.
pub(crate) fn cube26_nominal() -> Vec<[f64; 3]> {
    let mut dirs = PAPER_FACES.to_vec();
    let mut edges = Vec::new();
    let mut vertices = Vec::new();
    for x in [-1.0, 0.0, 1.0] {
        for y in [-1.0, 0.0, 1.0] {
            for z in [-1.0, 0.0, 1.0] {
                let v = DVec3::new(x, y, z);
                match v.to_array().iter().filter(|c| **c != 0.0).count() {
                    2 => edges.push(v.normalize().to_array()),
                    3 => vertices.push(v.normalize().to_array()),
                    _ => {}
                }
            }
        }
    }
    dirs.extend(edges);
    dirs.extend(vertices);
    dirs
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // pairs of poses read best indexed
mod tests {
    use super::*;

    fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        DVec3::from_array(a).dot(DVec3::from_array(b))
    }

    /// The angle between two unit vectors, accurate near 0 and 180° (`acos` of a dot product of
    /// 1 - 2e-16 is already 1.2e-6°).
    fn angle_deg(a: [f64; 3], b: [f64; 3]) -> f64 {
        let (a, b) = (DVec3::from_array(a), DVec3::from_array(b));
        a.cross(b).length().atan2(a.dot(b)).to_degrees()
    }

    #[test]
    fn plans_parse_and_display() {
        for plan in [Plan::Paper24, Plan::Cube26, Plan::Random(1), Plan::Random(500)] {
            assert_eq!(plan.to_string().parse::<Plan>(), Ok(plan));
        }
        assert_eq!(" Paper24 ".parse::<Plan>(), Ok(Plan::Paper24));
        assert_eq!("random:0".parse::<Plan>(), Err(ParsePlanError::InvalidCount("0".into())));
        assert_eq!("random:x".parse::<Plan>(), Err(ParsePlanError::InvalidCount("x".into())));
        assert_eq!("random:-3".parse::<Plan>(), Err(ParsePlanError::InvalidCount("-3".into())));
        assert_eq!("cube27".parse::<Plan>(), Err(ParsePlanError::UnknownPlan("cube27".into())));
        assert!(ParsePlanError::UnknownPlan("x".into()).to_string().contains("paper24"));
    }

    #[test]
    fn directions_are_unit_vectors() {
        for plan in [Plan::Paper24, Plan::Cube26, Plan::Random(100)] {
            let dirs = plan_directions(&plan, 3);
            assert_eq!(dirs.len(), plan.pose_count());
            for d in dirs {
                assert!((dot(d, d).sqrt() - 1.0).abs() < 1e-12, "{plan}: {d:?}");
            }
        }
    }

    #[test]
    fn paper24_clusters_into_six_directions() {
        let faces =
            [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];
        for seed in 0..20 {
            let dirs = plan_directions(&Plan::Paper24, seed);
            assert_eq!(dirs.len(), 24);
            for (f, face) in faces.iter().enumerate() {
                let group = &dirs[4 * f..4 * f + 4];
                for a in group {
                    // Flip error (up to ~2.8°) plus tilt (1.5°) from the nominal face.
                    assert!(angle_deg(*a, *face) < 4.5, "seed {seed} face {f}: {a:?}");
                    for b in group {
                        assert!(angle_deg(*a, *b) <= 2.0 * DEFAULT_TILT_DEG + 1e-9, "seed {seed} face {f}");
                    }
                }
                // The tilt is seen from four sides: the turns are not identical.
                assert!(angle_deg(group[0], group[2]) > 2.9, "seed {seed} face {f}");
            }
            for i in 0..24 {
                for j in 0..24 {
                    if i / 4 != j / 4 {
                        assert!(angle_deg(dirs[i], dirs[j]) > 80.0);
                    }
                }
            }
        }
    }

    #[test]
    fn cube26_has_26_distinct_directions() {
        let nominal = cube26_nominal();
        for seed in 0..20 {
            let dirs = plan_directions(&Plan::Cube26, seed);
            assert_eq!(dirs.len(), 26);
            for (d, n) in dirs.iter().zip(&nominal) {
                assert!(angle_deg(*d, *n) < 4.5);
            }
            for i in 0..26 {
                for j in i + 1..26 {
                    assert!(angle_deg(dirs[i], dirs[j]) > 25.0, "seed {seed}: {i} and {j}");
                }
            }
        }
    }

    #[test]
    fn random_directions_cover_the_sphere() {
        let dirs = plan_directions(&Plan::Random(4000), 11);
        let n = dirs.len() as f64;
        let mean = dirs.iter().fold([0.0; 3], |acc, d| [acc[0] + d[0] / n, acc[1] + d[1] / n, acc[2] + d[2] / n]);
        assert!(dot(mean, mean).sqrt() < 0.05, "{mean:?}");
        for axis in 0..3 {
            let upper = dirs.iter().filter(|d| d[axis] > 0.5).count() as f64 / n;
            assert!((upper - 0.25).abs() < 0.03, "axis {axis}: {upper}"); // a cap of height 1/2
        }
    }

    #[test]
    fn zero_tilt_and_flip_give_exact_faces() {
        let dirs = plan_directions_with(&Plan::Paper24, 5, 0.0, 0.0);
        assert!(dirs[0..4].iter().all(|d| angle_deg(*d, [0.0, 0.0, 1.0]) < 1e-6));
        assert!(dirs[8..12].iter().all(|d| angle_deg(*d, [0.0, 0.0, -1.0]) < 1e-6));
        assert!(dirs[20..24].iter().all(|d| angle_deg(*d, [0.0, -1.0, 0.0]) < 1e-6));
    }
}
