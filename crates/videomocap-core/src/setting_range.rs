//! The ranges a numeric setting must lie in, shared by the tracker's and the lift's settings
//! checks so both word a refusal alike.

/// The range a setting must lie in to mean something.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Range {
    /// Finite and above 0.
    Positive,
    /// Finite, 0 or more.
    NonNegative,
    /// Finite, 0 or more, below 1 (a fraction taken off a length, which must stay positive).
    Fraction,
    /// Between 0 and 1, both included.
    Unit,
    /// Above 0 and at most 180 (an angle between two directions, degrees).
    HalfTurn,
}

impl Range {
    /// Whether `v` lies in the range.
    fn holds(self, v: f64) -> bool {
        v.is_finite()
            && match self {
                Range::Positive => v > 0.0,
                Range::NonNegative => v >= 0.0,
                Range::Fraction => (0.0..1.0).contains(&v),
                Range::Unit => (0.0..=1.0).contains(&v),
                Range::HalfTurn => v > 0.0 && v <= 180.0,
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
            Range::Fraction => "0 or more and below 1",
            Range::Unit => "between 0 and 1",
            Range::HalfTurn => "above 0 and at most 180",
        }
    }
}
