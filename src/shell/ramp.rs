//! A load or motion factor as a function of time (issue 10 item 2): 0 before
//! `start`, rising linearly to 1 at `end`, 1 after; a step at `start` when
//! `end == start`. Within one linear piece its Taylor series in a = t − t0 is
//! exact with two terms; a step of the series in time must not cross a kink
//! ([`Ramp::kinks`]).

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ramp {
    pub start: f64,
    pub end: f64,
}

impl Ramp {
    /// Full from t = 0 on.
    pub const FULL: Ramp = Ramp {
        start: 0.0,
        end: 0.0,
    };

    /// The factor at t (at a step, the value after it).
    pub fn value(&self, t: f64) -> f64 {
        if t < self.start {
            0.0
        } else if t >= self.end {
            1.0
        } else {
            (t - self.start) / (self.end - self.start)
        }
    }

    /// d(value)/dt on the piece that starts at t (right derivative).
    pub fn rate(&self, t: f64) -> f64 {
        if t >= self.start && t < self.end {
            1.0 / (self.end - self.start)
        } else {
            0.0
        }
    }

    /// Times where the factor is not smooth, in increasing order.
    pub fn kinks(&self) -> Vec<f64> {
        if self.end > self.start {
            vec![self.start, self.end]
        } else {
            vec![self.start]
        }
    }

    /// Whether the factor changes after t = 0 (a ramp, or a step at t > 0).
    pub fn varies(&self) -> bool {
        self.end > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_rate_and_kinks_of_a_ramp() {
        let r = Ramp {
            start: 1.0,
            end: 3.0,
        };
        assert_eq!(
            [0.5, 1.0, 2.0, 3.0, 4.0].map(|t| r.value(t)),
            [0.0, 0.0, 0.5, 1.0, 1.0]
        );
        assert_eq!(
            [0.5, 1.0, 2.9, 3.0].map(|t| r.rate(t)),
            [0.0, 0.5, 0.5, 0.0]
        );
        assert_eq!(r.kinks(), vec![1.0, 3.0]);
        assert!(r.varies() && !Ramp::FULL.varies());
        assert_eq!(Ramp::FULL.value(0.0), 1.0);
    }
}
