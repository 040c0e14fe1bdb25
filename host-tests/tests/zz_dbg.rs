use accelcal_host::diagnose::{DiagnoseOptions, diagnose};
use accelcal_host::sim::scenario::{EffectClass, generate, random_scenario, to_table};
#[test]
fn dbg() {
    let seed: u64 = std::env::var("S").unwrap().parse().unwrap();
    let class = match std::env::var("C").unwrap().as_str() { "motion" => EffectClass::Motion, "cn" => EffectClass::ColoredNoise, _ => EffectClass::Drift };
    let table = to_table(&generate(&random_scenario(class, seed)), "x").unwrap();
    let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
    println!("{}", d.to_text());
}
