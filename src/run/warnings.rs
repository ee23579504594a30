//! What a finished run says aloud about its contact solve: the warning `ricochet run` prints
//! (and a library caller may show) when Lagrange contact steps did not converge.

/// The warning for a run whose Lagrange contact did not converge in some steps (their last
/// sweep still changed a gap by more than the tolerance after [`crate::contact::MAX_SWEEPS`]
/// sweeps), naming how many, the largest residual where the backend measures it, and the
/// tolerance of the backend that ran: [`crate::contact::SWEEP_TOLERANCE`] on the CPU reference,
/// on the GPU the step's, from [`crate::gpu::contact::solve::STOP_FLOOR`] to 1 times
/// [`crate::gpu::contact::solve::TOLERANCE`] by the step's penetration. From the summary's `backend`, `steps`,
/// `contact_unconverged` and `contact_residual_max`; `None` when every step converged.
pub fn convergence_warning(
    backend: &str,
    steps: u64,
    unconverged: u64,
    residual: Option<f64>,
) -> Option<String> {
    if unconverged == 0 {
        return None;
    }
    let tolerance = if backend == "gpu" {
        use crate::gpu::contact::solve::{STOP_FLOOR, TOLERANCE};
        format!(
            "{:.0e} to {TOLERANCE:.0e} by the step's penetration",
            STOP_FLOOR * TOLERANCE
        )
    } else {
        format!("{:.0e}", crate::contact::SWEEP_TOLERANCE)
    };
    let residual = match residual {
        Some(r) => format!("with a residual up to {r:.2e} of the search margin"),
        None => "(this backend does not measure the residual)".to_string(),
    };
    Some(format!(
        "the Lagrange contact did not converge in {} of {} steps: their sweeps stopped at the \
         limit ({} a solve) {residual} (the largest gap change of a step's last sweep; tolerance \
         {})",
        unconverged,
        steps,
        crate::contact::MAX_SWEEPS,
        tolerance
    ))
}

#[cfg(test)]
mod tests {
    use super::convergence_warning;

    #[test]
    fn names_the_steps_the_residual_and_the_backends_tolerance() {
        assert_eq!(convergence_warning("cpu", 401, 0, Some(3e-6)), None);
        let w = convergence_warning("cpu", 401, 7, Some(3.4e-5)).expect("a warning");
        assert!(w.contains("in 7 of 401 steps"), "{w}");
        assert!(w.contains("up to 3.40e-5 of the search margin"), "{w}");
        assert!(
            w.contains(&format!(
                "tolerance {:.0e}",
                crate::contact::SWEEP_TOLERANCE
            )),
            "{w}"
        );
        assert!(
            w.contains(&format!("({} a solve)", crate::contact::MAX_SWEEPS)),
            "{w}"
        );
        let g = convergence_warning("gpu", 10, 2, None).expect("a warning");
        assert!(g.contains("does not measure the residual"), "{g}");
        assert!(
            g.contains("tolerance 1e-5 to 1e-4 by the step's penetration"),
            "{g}"
        );
    }
}
