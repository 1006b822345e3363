//! Property tests over random serial chains with degenerate geometry on purpose: intersecting,
//! parallel, antiparallel, coincident, skew, near-parallel, prismatic, axes through the origin,
//! a tip on the last axis. The oracle is the product of exponentials of the axis lines, which
//! shares no code with the DH construction.

use std::f64::consts::{FRAC_PI_2, PI};

use dh_core::pose::pose_error;
use dh_core::{
    compare, extract, Convention, JointAxis, JointKind, Limits, Line, Relation, Tolerance, Warning,
};
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use proptest::prelude::*;

/// How the next axis relates to the previous one.
#[derive(Clone, Copy, Debug)]
enum Link {
    Intersecting,
    Parallel,
    Antiparallel,
    Coincident,
    Skew,
    NearParallel,
    ThroughOrigin,
}

fn link() -> impl Strategy<Value = Link> {
    prop_oneof![
        Just(Link::Intersecting),
        Just(Link::Parallel),
        Just(Link::Antiparallel),
        Just(Link::Coincident),
        Just(Link::Skew),
        Just(Link::NearParallel),
        Just(Link::ThroughOrigin),
    ]
}

fn unit_vector() -> impl Strategy<Value = Vector3<f64>> {
    (0.0..2.0 * PI, -1.0..1.0f64).prop_map(|(phi, z): (f64, f64)| {
        let r = (1.0 - z * z).sqrt();
        Vector3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

fn perpendicular(e: &Vector3<f64>, angle: f64) -> Vector3<f64> {
    let helper = if e.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = e.cross(&helper).normalize();
    let v = e.cross(&u);
    u * angle.cos() + v * angle.sin()
}

#[derive(Clone, Debug)]
struct Chain {
    axes: Vec<JointAxis>,
    tip: Isometry3<f64>,
}

/// A random chain of 1 to `max` joints.
fn serial_chain(max: usize) -> impl Strategy<Value = Chain> {
    let step = (
        link(),
        unit_vector(),
        0.0..2.0 * PI,
        -0.6..0.6f64,
        0.05..0.6f64,
        prop::bool::weighted(0.2),
        1e-7..5e-5f64,
    );
    (
        unit_vector(),
        prop::collection::vec(step, 1..=max),
        unit_vector(),
        -0.5..0.5f64,
        prop::bool::ANY,
        0.0..2.0 * PI,
    )
        .prop_map(
            |(first_dir, steps, tip_dir, tip_along, tip_on_axis, tip_spin)| {
                let mut axes: Vec<JointAxis> = Vec::new();
                let (mut point, mut dir) = (Vector3::new(0.1, -0.2, 0.3), first_dir);
                for (i, (kind, rand_dir, spin, along, offset, prismatic, tilt)) in
                    steps.into_iter().enumerate()
                {
                    if i > 0 {
                        let side = perpendicular(&dir, spin);
                        match kind {
                            Link::Intersecting => {
                                point += dir * along;
                                dir = (rand_dir - dir * rand_dir.dot(&dir) * 0.5).normalize();
                            }
                            Link::Parallel => point += side * offset + dir * along,
                            Link::Antiparallel => {
                                point += side * offset;
                                dir = -dir;
                            }
                            Link::Coincident => {
                                point += dir * along;
                                if spin > PI {
                                    dir = -dir;
                                }
                            }
                            Link::Skew => {
                                point += side * offset + dir * along;
                                dir = rand_dir;
                            }
                            Link::NearParallel => {
                                point += side * offset;
                                // Tilt inside the plane of the two axes: the ill-conditioned way.
                                dir = (dir + side * tilt).normalize();
                            }
                            Link::ThroughOrigin => {
                                point = Vector3::zeros();
                                dir = rand_dir;
                            }
                        }
                    }
                    axes.push(JointAxis {
                        name: format!("j{}", i + 1),
                        kind: if prismatic {
                            JointKind::Prismatic
                        } else {
                            JointKind::Revolute
                        },
                        line: Line::through(point, dir).unwrap(),
                        limits: Some(if prismatic {
                            Limits {
                                lower: -0.3,
                                upper: 0.3,
                            }
                        } else {
                            Limits {
                                lower: -PI,
                                upper: PI,
                            }
                        }),
                        mimic: None,
                    });
                }
                let last = axes.last().unwrap().line;
                let origin = if tip_on_axis {
                    last.point() + last.direction() * tip_along
                } else {
                    last.point()
                        + perpendicular(&last.direction(), tip_spin) * 0.1
                        + last.direction() * tip_along
                };
                let rot = UnitQuaternion::from_axis_angle(&Unit::new_normalize(tip_dir), tip_spin);
                Chain {
                    axes,
                    tip: Isometry3::from_parts(Translation3::from(origin), rot),
                }
            },
        )
}

/// Product of exponentials: each joint moves everything after it about (along) its line.
fn poe(chain: &Chain, q: &[f64]) -> Isometry3<f64> {
    let mut t = Isometry3::identity();
    for (ax, &qi) in chain.axes.iter().zip(q) {
        let e = ax.line.direction();
        let motion = match ax.kind {
            JointKind::Revolute => {
                let c = ax.line.point();
                Isometry3::translation(c.x, c.y, c.z)
                    * Isometry3::rotation(e * qi)
                    * Isometry3::translation(-c.x, -c.y, -c.z)
            }
            JointKind::Prismatic => Isometry3::translation(e.x * qi, e.y * qi, e.z * qi),
        };
        t *= motion;
    }
    t * chain.tip
}

fn cases() -> u32 {
    std::env::var("URDF_DH_PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(512)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    /// With rounding-level tolerances every chain is exact in both conventions: FK of the table
    /// equals the product of exponentials to 1e-12 relative to the chain's size, at 50 random
    /// joint values, and within the extraction's own bound.
    #[test]
    fn fk_of_the_table_is_the_chain(chain in serial_chain(10)) {
        let tol = Tolerance::new(1e-12, 1e-12).unwrap();
        for convention in [Convention::Standard, Convention::Modified] {
            let ex = extract(&chain.axes, &chain.tip, tol, convention).unwrap();
            let ill = ex.warnings.iter().any(|w| matches!(w, Warning::IllConditioned { .. }));
            let dev = compare(&ex.table, |q| poe(&chain, q), 50, 7).unwrap();
            let size = ex.table.size().max(1.0);
            // Near-parallel pairs at rounding tolerance are exact but ill-conditioned: their
            // huge offsets cancel only to about eps * offset.
            let slack = if ill { 1e-9 } else { 1e-12 };
            prop_assert!(dev.max_position_error <= slack * size, "{convention}: {dev:?} size {size}");
            prop_assert!(dev.max_orientation_error <= slack.max(1e-12), "{convention}: {dev:?}");
            if !ill {
                prop_assert!(dev.max_position_error <= ex.bound.position, "{dev:?} > {:?}", ex.bound);
            }
            let (dp, dr) = pose_error(&ex.table.fk(&vec![0.0; chain.axes.len()]).unwrap(), &chain.tip);
            prop_assert!(dp <= 1e-12 * size && dr <= 1e-12);
        }
    }

    /// At the default tolerance near-parallel pairs snap: the table stays sane (no offset far
    /// beyond the chain) and the FK deviation stays within the reported bound.
    #[test]
    fn snapped_tables_are_sane_and_within_their_bound(chain in serial_chain(8)) {
        for convention in [Convention::Standard, Convention::Modified] {
            let ex = extract(&chain.axes, &chain.tip, Tolerance::default(), convention).unwrap();
            let reach: f64 = 2.0 + chain.axes.len() as f64 * 1.5;
            // Row 1's offset is absorbed in the base; the last row's x comes from the tip frame.
            let n = ex.table.rows.len();
            for r in ex.table.rows.iter().take(n.saturating_sub(1)).skip(1) {
                let t = r.theta.abs();
                prop_assert!(t <= FRAC_PI_2 + 1e-4 || r.a == 0.0 && t > PI - 1e-4 || r.kind == JointKind::Prismatic,
                    "offsets stay within 90 degrees where the sign of x is free: {r:?}");
            }
            // Snapped (parallel-class) and intersecting pairs never put a common normal far
            // from the robot; skew pairs a few degrees from parallel legitimately do. A pair's
            // own normal is its `a` (row `first` in the standard convention, `first + 1` in
            // Craig's). `d` of row `first` runs along its axis from the previous pair's normal
            // to this one's, so it is bounded only when both normals are anchored near the
            // robot: an intersecting pair's normal sits at the intersection, a parallel-class
            // pair's goes through the previous origin (README), so it is anchored when the
            // previous one is, and a skew pair's may lie far out (found at 10^4 and 2·10^5
            // cases: an intersecting pair after a skew pair 2.6 degrees from antiparallel,
            // and after a parallel pair that followed such a skew pair; their rows' d is 12 m
            // and 15 m, exactly as the geometry says).
            let relation = |first: usize| {
                ex.pairs
                    .iter()
                    .find(|p| p.first == first)
                    .map(|p| p.geometry.relation)
            };
            let near = |first: usize| relation(first).is_some_and(|r| r != Relation::Skew);
            let mut anchored = Vec::with_capacity(ex.pairs.len());
            for first in 0..n.saturating_sub(1) {
                let previous = first == 0 || anchored[first - 1];
                anchored.push(match relation(first) {
                    Some(Relation::Skew) | None => false,
                    Some(Relation::Intersecting) => true,
                    Some(_) => previous,
                });
            }
            for p in ex.pairs.iter().filter(|p| near(p.first)) {
                let own = match convention {
                    Convention::Standard => &ex.table.rows[p.first],
                    Convention::Modified => &ex.table.rows[p.first + 1],
                };
                prop_assert!(own.a.abs() < reach, "{p:?} {own:?}");
                let r = &ex.table.rows[p.first];
                if anchored[p.first] && (p.first == 0 || anchored[p.first - 1]) {
                    prop_assert!(r.d.abs() < reach, "{p:?} {r:?}");
                }
            }
            // Within what the snaps can cost; the verification bound is that, capped at 1 mm /
            // 1 mrad, beyond which the table (rightly) fails its verification.
            let dev = compare(&ex.table, |q| poe(&chain, q), 50, 11).unwrap();
            prop_assert!(dev.max_position_error <= ex.cost.position, "{dev:?} > {:?}", ex.cost);
            prop_assert!(dev.max_orientation_error <= ex.cost.orientation, "{dev:?} > {:?}", ex.cost);
            let within = dev.max_position_error <= ex.bound.position
                && dev.max_orientation_error <= ex.bound.orientation;
            prop_assert!(
                within || ex.cost.position > ex.bound.position || ex.cost.orientation > ex.bound.orientation,
                "{dev:?} beyond an uncapped bound {:?}", ex.bound
            );
        }
    }

    /// Converting a table between conventions never changes its kinematics.
    #[test]
    fn conversion_keeps_kinematics(chain in serial_chain(8)) {
        let ex = extract(&chain.axes, &chain.tip, Tolerance::default(), Convention::Standard).unwrap();
        let md = ex.table.to_convention(Convention::Modified);
        let back = md.to_convention(Convention::Standard);
        for other in [&md, &back] {
            let dev = compare(&ex.table, |q| other.fk(q).unwrap(), 20, 3).unwrap();
            prop_assert!(dev.max_position_error <= 1e-12 * ex.table.size().max(1.0));
            prop_assert!(dev.max_orientation_error <= 1e-12);
        }
    }
}
