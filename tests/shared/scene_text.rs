//! Pieces of scene text shared by the CPU and GPU suites: the `[[material]]` table named
//! "steel" (linear elastic, E = 2.1e11 Pa, rho = 7850 kg/m^3) that their scenes write, with
//! nu = 0.3 ([`STEEL`], `steel!()` for `concat!`, [`steel_of`] another material model) or nu = 0 ([`STEEL_NU0`], the rods), and
//! the `[run]` table of a run at a fixed step ([`fixed_step_run`]). None ends in a line break.
#![allow(dead_code, unused_macros)]

/// The `[[material]]` table of [`STEEL`] as a literal, for `concat!`.
macro_rules! steel {
    () => {
        "[[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\ndensity = 7850.0\n\
         youngs_modulus = 2.1e11\npoisson_ratio = 0.3"
    };
}

/// The `[[material]]` table of the tests' steel with nu = 0.3.
pub const STEEL: &str = steel!();

/// The `[[material]]` table of the tests' steel (nu = 0.3) with the material model `model`:
/// [`STEEL`] for `linear_elastic`.
pub fn steel_of(model: &str) -> String {
    STEEL.replace("\"linear_elastic\"", &format!("\"{model}\""))
}

/// The `[[material]]` table of the tests' steel with nu = 0 (the rods of the wave and impact
/// tests).
pub const STEEL_NU0: &str = "[[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\n\
                             density = 7850.0\nyoungs_modulus = 2.1e11\npoisson_ratio = 0.0";

/// The `[run]` table of a run to `end` at the fixed step `dt`, a history row every step, bulk
/// viscosity off.
pub fn fixed_step_run(end: f64, dt: f64) -> String {
    format!(
        "[run]\nend_time = {end:e}\ntime_step = {dt:e}\nhistory_interval = {dt:e}\n\
         bulk_viscosity = {{ linear = 0.0, quadratic = 0.0 }}"
    )
}
