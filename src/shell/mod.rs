//! 3D shell element with EAS (quadratic kinematics), quadrature.
