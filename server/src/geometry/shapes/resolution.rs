//! Grid resolutions that give a shape about the requested number of triangles.

/// The resolution whose triangle count is closest to `target`; on a tie, the earlier candidate.
/// Candidates come as (resolution, triangle count); the search stops at the first candidate past
/// twice the target (counts grow with the resolution).
pub(super) fn closest_resolution<R: Copy>(
    target: usize,
    candidates: impl Iterator<Item = (R, usize)>,
) -> R {
    let mut best: Option<(usize, R)> = None;
    for (resolution, count) in candidates {
        let error = count.abs_diff(target);
        if best.is_none_or(|(e, _)| error < e) {
            best = Some((error, resolution));
        }
        if count > target.saturating_mul(2) {
            break;
        }
    }
    best.expect("every shape offers at least one resolution").1
}

/// Number of equal steps of about `spacing` along `length`: at least 1, at most `cap` (which
/// bounds the mesh size whatever the proportions).
pub(super) fn steps(length: f64, spacing: f64, cap: usize) -> usize {
    ((length / spacing).round() as usize).clamp(1, cap.max(1))
}

/// (segments around, stacks from pole to pole) of a UV sphere: 2 * segments * (stacks - 1)
/// triangles. Segments stay between 1.5 and 2.5 times the stacks (2 gives square cells at the
/// equator), which lets most counts be met exactly, such as the paper's 132 and 2,652.
pub(super) fn sphere_resolution(target: usize) -> (usize, usize) {
    let count = |n: usize, s: usize| 2 * n * (s - 1);
    closest_resolution(
        target,
        (2usize..).flat_map(|s| {
            let (lo, hi) = ((3 * s).div_ceil(2).max(3), (5 * s) / 2);
            let ideal = target / (2 * (s - 1));
            [ideal, ideal + 1]
                .into_iter()
                .map(move |n| n.clamp(lo, hi.max(lo)))
                .map(move |n| ((n, s), count(n, s)))
        }),
    )
}

/// (nu, nv) of a torus with nu / nv = 2.5: 2 * nu * nv triangles.
pub(super) fn torus_resolution(target: usize) -> (usize, usize) {
    closest_resolution(
        target,
        (3usize..).map(|nu| {
            let nv = ((nu as f64 / 2.5).round() as usize).max(3);
            ((nu, nv), 2 * nu * nv)
        }),
    )
}
