//! The stiffness and mass matrices against their defining properties.

use crate::common::Inside;

use necklace::morse::{cotangent_stiffness, lumped_mass};
use necklace::shapes::{Shape, ShapeKind};
use necklace::volume::{stuff_volume, StuffingOptions};
use necklace::{TetMesh, VertexKind};

fn torus_mesh() -> TetMesh {
    stuff_volume(
        &Inside(Shape::new(ShapeKind::Torus)),
        &StuffingOptions::new(0.08),
    )
    .unwrap()
    .mesh
}

#[test]
fn stiffness_is_symmetric_with_zero_row_sums() {
    let m = torus_mesh();
    let l = cotangent_stiffness(&m);
    for i in 0..l.n {
        let mut sum = 0.0;
        let mut scale = 0.0f64;
        for (j, v) in l.row(i) {
            assert!(
                (v - l.get(j as usize, i)).abs() <= 1e-12 * v.abs().max(1e-30),
                "not symmetric"
            );
            sum += v;
            scale = scale.max(v.abs());
        }
        assert!(sum.abs() <= 1e-12 * scale, "row {i} sums to {sum}");
        assert!(l.get(i, i) > 0.0);
    }
}

#[test]
fn stiffness_is_exact_on_linear_functions() {
    let m = torus_mesh();
    let l = cotangent_stiffness(&m);
    let a = [0.3, -1.2, 0.7];
    let f: Vec<f64> = m
        .positions
        .iter()
        .map(|p| a[0] * p[0] + a[1] * p[1] + a[2] * p[2] + 0.5)
        .collect();
    let lf = l.mul_vec(&f);
    // Δ of a linear function is 0: only boundary rows carry (flux) terms.
    for (i, &value) in lf.iter().enumerate() {
        if m.kinds[i] == VertexKind::Interior {
            assert!(value.abs() < 1e-10, "interior row {i}: {value}");
        }
    }
    // fᵀ L f = ∫ |∇f|² = |a|² · volume.
    let energy: f64 = f.iter().zip(&lf).map(|(x, y)| x * y).sum();
    let expected = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) * m.volume();
    assert!(
        (energy - expected).abs() < 1e-9 * expected,
        "{energy} vs {expected}"
    );
}

#[test]
fn stiffness_is_positive_semidefinite_and_mass_sums_to_volume() {
    let m = torus_mesh();
    let l = cotangent_stiffness(&m);
    // A fixed pseudo-random field (LCG).
    let mut state = 12345u64;
    let f: Vec<f64> = (0..l.n)
        .map(|_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect();
    let energy: f64 = f.iter().zip(l.mul_vec(&f)).map(|(x, y)| x * y).sum();
    assert!(energy > 0.0);
    let mass = lumped_mass(&m);
    let total: f64 = mass.iter().sum();
    assert!((total - m.volume()).abs() < 1e-12 * m.volume());
    assert!(mass.iter().all(|&x| x > 0.0));
}

mod smoothing {
    use super::*;
    use necklace::morse::{implicit_step, Preconditioner, SolverOptions};

    fn boundary(m: &TetMesh) -> Vec<bool> {
        m.kinds.iter().map(|&k| k != VertexKind::Interior).collect()
    }

    /// A bumpy field that is zero on the boundary.
    fn bumpy_field(m: &TetMesh, fixed: &[bool]) -> Vec<f64> {
        m.positions
            .iter()
            .zip(fixed)
            .map(|(p, &b)| {
                if b {
                    0.0
                } else {
                    (7.0 * p[0]).sin() * (5.0 * p[1]).cos() + 1.0
                }
            })
            .collect()
    }

    #[test]
    fn a_linear_field_with_its_boundary_values_is_a_fixed_point() {
        let m = torus_mesh();
        let (l, mass, fixed) = (cotangent_stiffness(&m), lumped_mass(&m), boundary(&m));
        let f: Vec<f64> = m
            .positions
            .iter()
            .map(|p| 2.0 * p[0] - p[2] + 1.0)
            .collect();
        let (g, report) = implicit_step(&l, &mass, &fixed, &f, 0.01, &SolverOptions::default());
        assert!(report.converged, "{report:?}");
        for (a, b) in f.iter().zip(&g) {
            assert!((a - b).abs() < 1e-8, "{a} -> {b}");
        }
    }

    #[test]
    fn a_step_lowers_the_dirichlet_energy_and_keeps_boundary_values() {
        let m = torus_mesh();
        let (l, mass, fixed) = (cotangent_stiffness(&m), lumped_mass(&m), boundary(&m));
        let f = bumpy_field(&m, &fixed);
        let energy = |x: &[f64]| -> f64 { x.iter().zip(l.mul_vec(x)).map(|(a, b)| a * b).sum() };
        let (g, report) = implicit_step(&l, &mass, &fixed, &f, 0.01, &SolverOptions::default());
        assert!(report.converged && report.iterations > 0, "{report:?}");
        assert!(energy(&g) < energy(&f));
        for i in 0..f.len() {
            if fixed[i] {
                assert_eq!(g[i], 0.0);
            }
        }
    }

    #[test]
    fn a_step_does_not_depend_on_the_thread_count() {
        let m = torus_mesh();
        let (l, mass, fixed) = (cotangent_stiffness(&m), lumped_mass(&m), boundary(&m));
        let f: Vec<f64> = m.positions.iter().map(|p| p[0] * p[1] + p[2]).collect();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| implicit_step(&l, &mass, &fixed, &f, 0.01, &SolverOptions::default()).0)
        };
        assert_eq!(run(1), run(3));
    }

    #[test]
    fn more_stored_solutions_give_the_same_fields_in_fewer_iterations() {
        let m = torus_mesh();
        let run = |history: usize| {
            let options = SolverOptions {
                history: Some(history),
                ..SolverOptions::default()
            };
            scale_space(&m, options, 1.5)
        };
        let (one, few) = (run(1), run(6));
        for (a, b) in one.0.iter().zip(&few.0) {
            assert!((a - b).abs() < 1e-7, "{a} against {b}");
        }
        assert!(
            few.1 < one.1,
            "{} iterations with six, {} with one",
            few.1,
            one.1
        );
    }

    fn with(preconditioner: Preconditioner) -> SolverOptions {
        SolverOptions {
            preconditioner,
            ..SolverOptions::default()
        }
    }

    /// A scale-space sequence of 12 heat steps (τ_k = t_k − t_{k−1}, t_k growing by
    /// `growth`) from a bumpy field: the last field, the iterations and the multigrid
    /// levels.
    fn scale_space(
        m: &TetMesh,
        options: SolverOptions,
        growth: f64,
    ) -> (Vec<f64>, usize, Option<Vec<usize>>) {
        use necklace::morse::HeatSolver;
        let (l, mass, fixed) = (cotangent_stiffness(m), lumped_mass(m), boundary(m));
        let f = bumpy_field(m, &fixed);
        let mut solver = HeatSolver::new(&l, &mass, &fixed, &f, 1e-4, options);
        let (mut g, mut iterations, mut previous_t) = (f.clone(), 0, 0.0);
        for k in 0..12 {
            let t = 1e-4 * growth.powi(k);
            solver.set_tau(t - previous_t);
            previous_t = t;
            let (next, report) = solver.step(&g);
            assert!(report.converged, "{report:?}");
            iterations += report.iterations;
            g = next;
        }
        (g, iterations, solver.multigrid().map(|h| h.sizes.clone()))
    }

    #[test]
    fn multigrid_gives_jacobis_fields_in_fewer_iterations() {
        let m = torus_mesh();
        let jacobi = scale_space(&m, with(Preconditioner::Jacobi), 2.0);
        let multigrid = scale_space(&m, with(Preconditioner::Multigrid), 2.0);
        assert!(jacobi.2.is_none());
        let sizes = multigrid.2.expect("a hierarchy");
        assert!(
            sizes.len() >= 2 && sizes.windows(2).all(|w| w[1] * 2 < w[0]),
            "{sizes:?}"
        );
        let largest = jacobi.0.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        for (a, b) in jacobi.0.iter().zip(&multigrid.0) {
            assert!((a - b).abs() < 1e-8 * largest, "{a} against {b}");
        }
        assert!(
            2 * multigrid.1 < jacobi.1,
            "{} multigrid iterations, {} Jacobi",
            multigrid.1,
            jacobi.1
        );
    }

    #[test]
    fn the_default_preconditioner_is_multigrid_only_within_its_sizes() {
        use necklace::morse::{MULTIGRID_MAX_UNKNOWNS, MULTIGRID_MIN_UNKNOWNS};
        let m = torus_mesh();
        let free = boundary(&m).iter().filter(|&&fixed| !fixed).count();
        assert!(free < MULTIGRID_MIN_UNKNOWNS);
        // Below the size the default solve is Jacobi's, to the bit.
        let auto = scale_space(&m, SolverOptions::default(), 2.0);
        assert_eq!(auto, scale_space(&m, with(Preconditioner::Jacobi), 2.0));
        let rule = |unknowns| Preconditioner::Auto.multigrid_for(unknowns);
        assert!(!rule(MULTIGRID_MIN_UNKNOWNS - 1) && rule(MULTIGRID_MIN_UNKNOWNS));
        assert!(rule(MULTIGRID_MAX_UNKNOWNS - 1) && !rule(MULTIGRID_MAX_UNKNOWNS));
        assert!(Preconditioner::Multigrid.multigrid_for(free));
        assert!(!Preconditioner::Jacobi.multigrid_for(usize::MAX));
    }

    #[test]
    fn multigrid_does_not_depend_on_the_thread_count() {
        let m = torus_mesh();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| scale_space(&m, with(Preconditioner::Multigrid), 2.0))
        };
        let (one, three) = (run(1), run(3));
        assert_eq!(one.0, three.0);
        assert_eq!(one.1, three.1);
    }
}
