//! The settings of a reference run and their checks: tolerances, the diffsol
//! method, and every option where we depart from a library's default, each
//! with its documented default (`anm reference ida|diffsol --help`, README
//! "Fair baselines").

use super::error::IdaError;

/// Error-test tolerances: weight of unknown i is 1 / (rtol |y_i| + atol_i).
#[derive(Clone, Debug, PartialEq)]
pub struct Tolerances {
    pub rtol: f64,
    /// Absolute tolerance of the differential unknowns (positions), m.
    pub atol: f64,
}

impl Tolerances {
    /// Checks rtol and atol; `atol` None follows rtol (atol = rtol: the
    /// positions are O(0.1..1) m, so rtol |y| and atol weigh alike).
    pub fn new(rtol: f64, atol: Option<f64>) -> Result<Self, IdaError> {
        let atol = atol.unwrap_or(rtol);
        positive("rtol", rtol)?;
        // Review 20: 2 and 1e-20 were accepted (the first tests nothing,
        // the second asks below the double's resolution).
        if !(1e-15..1.0).contains(&rtol) {
            return Err(IdaError::Input(format!(
                "--rtol must lie in [1e-15, 1), got {rtol:e}"
            )));
        }
        positive("atol", atol)?;
        Ok(Self { rtol, atol })
    }
}

/// Err naming the option unless `value` is positive and finite.
pub fn positive(name: &str, value: f64) -> Result<(), IdaError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(IdaError::Input(format!(
            "--{name} must be positive and finite, got {value:e}"
        )))
    }
}

/// How the algebraic unknowns (velocities, contact forces, and u_y on the
/// plane) enter the local error test.
///
/// Why this matters: in an index-1 DAE the algebraic unknowns z are
/// functions of the differential ones, z = phi(t, u), solved by the Newton
/// iteration at every step; their local error is phi_u times that of u. On
/// the friction scenes the slip velocity is v_x = V + g^-1(-R_T / (f
/// |R_N|_reg)), and where the friction capacity f |R_N|_reg is small (before
/// contact, |R_N|_reg = zeta) dv_x/du_x = k / (f zeta g'(v_s)) reaches
/// ~5e6 s^-1 at zeta = 1e-6 N: an error test on v_x at the tolerance of u_x
/// asks u_x for an accuracy 5e6 times finer than requested, which no step
/// size gives, and the solver falls to order 1 with tiny steps (issue 16:
/// 44,437 IDA steps at zeta = 1e-2 N, 43,753 of them error-test failures).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlgebraicControl {
    /// Algebraic unknowns out of the error test (IDA: IDASetSuppressAlg
    /// with the id vector). Their accuracy follows from that of u through
    /// the constraint solved by Newton to the nonlinear tolerance.
    Suppress,
    /// Algebraic unknowns in the error test with this absolute tolerance
    /// (the library default is the same atol as the differential unknowns).
    Atol(f64),
}

impl AlgebraicControl {
    /// Parses "suppress" or a positive number.
    pub fn parse(name: &str, s: &str) -> Result<Self, IdaError> {
        if s == "suppress" {
            return Ok(Self::Suppress);
        }
        let v: f64 = s.parse().map_err(|_| {
            IdaError::Input(format!(
                "--{name}: expected `suppress` or a positive number, got `{s}`"
            ))
        })?;
        positive(name, v)?;
        Ok(Self::Atol(v))
    }

    /// atol of the algebraic unknowns: `atol` of the differential ones when
    /// suppressed (the error test ignores them then), or the given value.
    pub fn atol(&self, atol: f64) -> f64 {
        match self {
            Self::Suppress => atol,
            Self::Atol(a) => *a,
        }
    }
}

impl std::fmt::Display for AlgebraicControl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Suppress => write!(f, "suppress"),
            Self::Atol(a) => write!(f, "{a:e}"),
        }
    }
}

/// The diffsol integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DiffsolMethod {
    /// Variable-order (1-5) BDF with a singular mass matrix.
    Bdf,
    /// ESDIRK34: the third-order, four-stage ESDIRK method of Jørgensen,
    /// Kristensen and Thomsen (arXiv:1803.01613), with its embedded error
    /// estimate, as shipped by diffsol.
    Esdirk,
}

impl DiffsolMethod {
    pub fn name(&self) -> &'static str {
        match self {
            Self::Bdf => "bdf",
            Self::Esdirk => "esdirk",
        }
    }
}

impl std::str::FromStr for DiffsolMethod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "bdf" => Ok(Self::Bdf),
            "esdirk" => Ok(Self::Esdirk),
            _ => Err(format!(
                "unknown diffsol method `{s}`: expected `bdf` or `esdirk`"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tolerances_are_checked_and_atol_follows_rtol() {
        assert_eq!(Tolerances::new(1e-8, None).unwrap().atol, 1e-8);
        assert_eq!(Tolerances::new(1e-8, Some(1e-6)).unwrap().atol, 1e-6);
        for (r, a, name) in [
            (0.0, None, "--rtol"),
            (-1e-8, None, "--rtol"),
            (f64::NAN, Some(1e-8), "--rtol"),
            (2.0, None, "--rtol"),
            (1e-20, None, "--rtol"),
            (1e-8, Some(f64::INFINITY), "--atol"),
            (1e-8, Some(-1.0), "--atol"),
        ] {
            let e = Tolerances::new(r, a).unwrap_err().to_string();
            assert!(e.contains(name), "{e}");
        }
    }

    #[test]
    fn algebraic_control_parses() {
        let p = |s| AlgebraicControl::parse("atol-algebraic", s);
        assert_eq!(p("suppress").unwrap(), AlgebraicControl::Suppress);
        assert_eq!(p("1e-6").unwrap(), AlgebraicControl::Atol(1e-6));
        for bad in ["-1", "0", "nan", "inf", "x"] {
            let e = p(bad).unwrap_err().to_string();
            assert!(e.contains("--atol-algebraic"), "{e}");
        }
        assert!("rk4".parse::<DiffsolMethod>().unwrap_err().contains("rk4"));
    }
}
