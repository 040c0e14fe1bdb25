//! The GA on the paper's test function (Fig. 3): success rates and mean best cost per generation.

use accelcal::ga::{Aga, Ga, GaConfig, Laga, Operators, SearchBox, Taga, rastrigin};
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

const POP: usize = 40;
const GENERATIONS: u32 = 100;
const SEEDS: u64 = 200;
const TARGET: f32 = 1e-3;

/// Best cost per generation (index 0 = initial population) of one seeded run.
fn trace<O: Operators>(operators: O, seed: u64) -> [f32; GENERATIONS as usize + 1] {
    let bounds = SearchBox::new([-5.12; 2], [5.12; 2]).unwrap();
    let config = GaConfig { operators, max_generations: GENERATIONS, ..GaConfig::DEFAULT };
    let mut ga: Ga<_, POP, 2, O> =
        Ga::new(config, bounds, Xoshiro128PlusPlus::seed_from_u64(seed), &rastrigin).unwrap();
    let mut out = [0.0; GENERATIONS as usize + 1];
    out[0] = ga.best_cost();
    for g in 1..=GENERATIONS as usize {
        ga.step(&rastrigin);
        out[g] = ga.best_cost();
    }
    out
}

fn success_and_mean<O: Operators>(operators: O) -> (usize, [f32; GENERATIONS as usize + 1]) {
    let mut successes = 0;
    let mut mean = [0.0; GENERATIONS as usize + 1];
    for seed in 0..SEEDS {
        let t = trace(operators, seed);
        successes += usize::from(t[GENERATIONS as usize] < TARGET);
        for (m, v) in mean.iter_mut().zip(t) {
            *m += v / SEEDS as f32;
        }
    }
    (successes, mean)
}

#[test]
fn taga_reaches_rastrigin_target_in_95_percent_of_200_seeds() {
    let (successes, _) = success_and_mean(Taga::PAPER);
    println!("TAGA: {successes}/{SEEDS} seeds below {TARGET} within {GENERATIONS} generations");
    assert!(successes * 100 >= 95 * SEEDS as usize, "{successes}/{SEEDS}");
}

#[test]
fn fig3_ranks_taga_before_laga_before_aga() {
    let mut results = Vec::new();
    let runs = [
        ("AGA", success_and_mean(Aga::PAPER)),
        ("LAGA", success_and_mean(Laga::PAPER)),
        ("TAGA", success_and_mean(Taga::PAPER)),
    ];
    for (name, (successes, mean)) in runs {
        println!(
            "{name}: success {successes}/{SEEDS}; mean best cost at gen 10 {:.3e}, 25 {:.3e}, 50 {:.3e}, 100 {:.3e}",
            mean[10], mean[25], mean[50], mean[100]
        );
        // The mean best never gets worse (elitism).
        assert!(mean.windows(2).all(|w| w[1] <= w[0] + 1e-6), "{name} best cost rose");
        results.push((name, successes, mean));
    }
    // The paper's Fig. 3 ranking: TAGA converges fastest, then LAGA, then AGA, at every checkpoint
    // (mean best cost over the seeds), and succeeds at least as often.
    for pair in results.windows(2) {
        let ((worse, s_worse, m_worse), (better, s_better, m_better)) = (&pair[0], &pair[1]);
        assert!(s_better >= s_worse, "{better} succeeds less often than {worse}");
        for g in [10, 25, 50, 100] {
            assert!(m_better[g] < m_worse[g], "{better} not ahead of {worse} at generation {g}");
        }
    }
}

#[test]
fn run_terminates_with_the_reason() {
    use accelcal::ga::Termination;
    let bounds = SearchBox::new([-5.12; 2], [5.12; 2]).unwrap();
    let cfg = GaConfig { target_cost: 0.5, max_generations: 500, ..GaConfig::DEFAULT };
    let mut ga: Ga<_, POP, 2> = Ga::new(cfg, bounds, Xoshiro128PlusPlus::seed_from_u64(3), &rastrigin).unwrap();
    let r = ga.run(&rastrigin);
    assert_eq!(r.termination, Termination::TargetReached);
    assert!(r.cost <= 0.5);
    assert_eq!(
        r.evaluations,
        POP as u32 * (1 + r.generations) - GaConfig::<Taga>::DEFAULT.elites as u32 * r.generations
    );

    let flat = |_: &[f32; 2]| 1.0f32;
    let cfg = GaConfig { stall_generations: 5, ..GaConfig::DEFAULT };
    let mut ga: Ga<_, POP, 2> = Ga::new(cfg, bounds, Xoshiro128PlusPlus::seed_from_u64(3), &flat).unwrap();
    let r = ga.run(&flat);
    assert_eq!((r.termination, r.generations), (Termination::Stalled, 5));

    let cfg = GaConfig { max_generations: 7, ..GaConfig::DEFAULT };
    let mut ga: Ga<_, POP, 2> = Ga::new(cfg, bounds, Xoshiro128PlusPlus::seed_from_u64(3), &rastrigin).unwrap();
    assert_eq!(ga.run(&rastrigin).termination, Termination::MaxGenerations);
}

#[test]
fn invalid_boxes_and_configs_are_typed_errors() {
    use accelcal::ga::GaError;
    assert_eq!(SearchBox::new([0.0, 1.0], [1.0, 1.0]), Err(GaError::InvalidInterval { dim: 1 }));
    assert_eq!(SearchBox::new([2.0], [1.0]), Err(GaError::InvalidInterval { dim: 0 }));
    assert_eq!(SearchBox::new([f32::NAN], [1.0]), Err(GaError::InvalidInterval { dim: 0 }));
    let bounds = SearchBox::new([-1.0; 2], [1.0; 2]).unwrap();
    let cfg = GaConfig { elites: 39, ..GaConfig::DEFAULT };
    let r = Ga::<_, POP, 2>::new(cfg, bounds, Xoshiro128PlusPlus::seed_from_u64(0), &rastrigin);
    assert!(matches!(r, Err(GaError::TooManyElites)));
}

#[test]
fn non_finite_costs_are_the_worst_and_never_win() {
    let bounds = SearchBox::new([-1.0; 2], [1.0; 2]).unwrap();
    let nan_left = |x: &[f32; 2]| if x[0] < 0.0 { f32::NAN } else { x[0] * x[0] + x[1] * x[1] };
    let mut ga: Ga<_, POP, 2> =
        Ga::new(GaConfig::DEFAULT, bounds, Xoshiro128PlusPlus::seed_from_u64(9), &nan_left).unwrap();
    let r = ga.run(&nan_left);
    assert!(r.best[0] >= 0.0 && r.cost.is_finite() && r.cost < 1e-3, "{r:?}");
}
