//! The ranges a numeric setting must lie in, shared by the tracker's and the lift's settings
//! checks so both word a refusal alike.

/// The range a setting must lie in to mean something.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Range {
    /// Finite and above 0.
    Positive,
    /// Finite, 0 or more.
    NonNegative,
    /// Between 0 and 1, both included.
    Unit,
}

impl Range {
    /// Whether `v` lies in the range.
    fn holds(self, v: f64) -> bool {
        v.is_finite()
            && match self {
                Range::Positive => v > 0.0,
                Range::NonNegative => v >= 0.0,
                Range::Unit => (0.0..=1.0).contains(&v),
            }
    }

    /// `Ok` when `v` lies in the range, else the range in words (for the caller's own typed
    /// error).
    pub(crate) fn check(self, v: f64) -> Result<(), &'static str> {
        if self.holds(v) {
            Ok(())
        } else {
            Err(self.want())
        }
    }

    /// The range in words, for an error message.
    fn want(self) -> &'static str {
        match self {
            Range::Positive => "a finite number above 0",
            Range::NonNegative => "a finite number, 0 or more",
            Range::Unit => "between 0 and 1",
        }
    }
}
