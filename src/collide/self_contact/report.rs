//! What self-contact did in one `resolve` (exact counts, for metrics, diagnostics and the bench).

/// Counts of one cloth-cloth pass of the collision stage (summed over substeps in `StepMetrics`,
/// except the largest zone, which is the largest seen).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SelfContactReport {
    /// Candidate pairs the broad phases handed to the narrow phase (vertex-triangle plus
    /// edge-edge, or vertex-vertex), summed over the passes.
    pub candidates: usize,
    /// Node tests the broad phase's hierarchy made to find them (its cost), summed.
    pub node_tests: usize,
    /// Close pairs answered by proximity repulsion.
    pub repulsions: usize,
    /// Pairs exempt from proximity because they are closer than their contact distance in the
    /// rest shape (a property of the mesh and thickness: the largest seen, not summed).
    pub exempt: usize,
    /// CCD passes run and crossing pairs they corrected.
    pub ccd_passes: usize,
    pub ccd_hits: usize,
    /// Impact zones formed by the fail-safe, and the vertices of the largest.
    pub zones: usize,
    pub largest_zone: usize,
    /// Pairs whose Coulomb friction slid in the passes' impulses (at its limit, the pair still
    /// slipping), summed over the passes.
    pub slipping: usize,
    /// Cloth-cloth passes run again because the first moved vertices into an obstacle.
    pub obstacle_retests: usize,
}

impl SelfContactReport {
    /// Adds one more pass (sums, and the largest zone).
    pub fn add(&mut self, o: &SelfContactReport) {
        self.candidates += o.candidates;
        self.node_tests += o.node_tests;
        self.repulsions += o.repulsions;
        self.exempt = self.exempt.max(o.exempt);
        self.ccd_passes += o.ccd_passes;
        self.ccd_hits += o.ccd_hits;
        self.zones += o.zones;
        self.largest_zone = self.largest_zone.max(o.largest_zone);
        self.obstacle_retests += o.obstacle_retests;
        self.slipping += o.slipping;
    }
}
