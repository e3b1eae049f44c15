//! Parameter names and the layout of the flat parameter vector.

use std::fmt;

/// A name prefix and the constructor of its parameter kind.
type Maker = (&'static str, fn(usize) -> Param);

/// Parameters per joint in the flat vector: θ, d, a, α, β.
pub const PARAMS_PER_JOINT: usize = 5;

/// Length of the flat parameter vector of a robot with `dof` joints: the joint parameters,
/// the six base and six tool parameters, one joint compliance per joint, the
/// [`HARMONIC_TERMS`] joint-angle harmonic coefficients per joint, then the
/// [`GRAVITY_POINTS`] gravity-basis coefficients per joint.
pub fn value_count(dof: usize) -> usize {
    PARAMS_PER_JOINT * dof + 12 + dof + HARMONIC_TERMS * dof + GRAVITY_POINTS * dof
}

/// The highest order of a joint-angle harmonic ([`Param::Harmonic`]).
pub const MAX_HARMONIC_ORDER: usize = 16;

/// Harmonic coefficients per joint ([`Param::Harmonic`]): `sin nq`, `cos nq` for each order
/// `n` from 1 to [`MAX_HARMONIC_ORDER`].
pub const HARMONIC_TERMS: usize = 2 * MAX_HARMONIC_ORDER;

/// The points of the mass-free gravity basis ([`Param::Gravity`]): the elbow, the wrist
/// centre and the tool point.
pub const GRAVITY_POINTS: usize = 3;

/// The name prefix of each gravity-basis point ([`Param::Gravity`]'s second index).
const GRAVITY_PREFIX: [&str; GRAVITY_POINTS] = ["ge", "gw", "gt"];

/// The name of harmonic term `k` of joint `j` (0-based): `hs`/`hc` for the first order,
/// `h{n}s`/`h{n}c` for order `n` ≥ 2, then the joint number.
fn harmonic_name(j: usize, k: usize) -> String {
    let (order, part) = (k / 2 + 1, ["s", "c"][k % 2]);
    if order == 1 {
        format!("h{part}{}", j + 1)
    } else {
        format!("h{order}{part}{}", j + 1)
    }
}

/// Parses a harmonic name (`hs3`, `hc3`, `h2s3`, `h12c1`): the joint (0-based) and term.
fn parse_harmonic(name: &str) -> Option<Param> {
    let rest = name.strip_prefix('h')?;
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    let order = if digits == 0 {
        1
    } else {
        let n: usize = rest[..digits].parse().ok()?;
        if !(2..=MAX_HARMONIC_ORDER).contains(&n) || rest.starts_with('0') {
            return None;
        }
        n
    };
    let rest = &rest[digits..];
    let part = match rest.as_bytes().first()? {
        b's' => 0,
        b'c' => 1,
        _ => return None,
    };
    let num = &rest[1..];
    if num.is_empty() || !num.bytes().all(|b| b.is_ascii_digit()) || num.starts_with('0') {
        return None;
    }
    let j: usize = num.parse().ok()?;
    Some(Param::Harmonic(j - 1, 2 * (order - 1) + part))
}

const PART: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];

/// One geometric parameter of a robot. Joint indices are 0-based inside (`Theta(0)` is
/// `theta1`); base and tool components are 0..6 for x, y, z, rx, ry, rz.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Param {
    /// Joint angle offset θ (rad).
    Theta(usize),
    /// Link offset d (mm).
    D(usize),
    /// Link length a (mm).
    A(usize),
    /// Link twist α (rad).
    Alpha(usize),
    /// Hayati's β (rad), for `dh_beta` and `mdh`.
    Beta(usize),
    /// Base frame component (x, y, z mm; rx, ry, rz rad, fixed X-Y-Z angles).
    Base(usize),
    /// Tool frame component, same form as the base.
    Tool(usize),
    /// Joint compliance `c_j` (rad/(N·m)): the joint deflects by `c_j τ_j` under the gravity
    /// torque `τ_j` of the links and the payload (elasto-geometric model, docs/formats.md
    /// "Elasto-geometric calibration"). Not part of [`Param::all`]: a study identifies it only when it asks to.
    Compliance(usize),
    /// Coefficient of a joint-angle harmonic (rad): joint `j`'s chain variable is offset by
    /// `Δq_j = Σ_n a_jn sin n q_j + b_jn cos n q_j` (encoder and gear eccentricity, and
    /// finer periodic errors of the drive); `Harmonic(j, k)` is `a_jn` for `k = 2(n − 1)`
    /// and `b_jn` for `k = 2(n − 1) + 1`, named `hs`, `hc` (n = 1), `h{n}s`, `h{n}c` (n ≥ 2)
    /// and the joint number (docs/formats.md "Joint-angle harmonics"). Not part of
    /// [`Param::all`]; revolute joints only.
    Harmonic(usize, usize),
    /// Coefficient of the mass-free gravity basis (rad per N·m): joint `j`'s chain variable is
    /// offset by `Δq_j = Σ_l k_jl τ_jl(q)`, `τ_jl` the torque about joint `j`'s axis of a
    /// weight of 1 N at the elbow (`l` = 0), the wrist centre (1) or the tool point (2)
    /// ([`crate::robot::gravity_basis`]); named `ge`, `gw`, `gt` and the joint number. Not
    /// part of [`Param::all`]; revolute joints only.
    Gravity(usize, usize),
}

impl Param {
    /// Every parameter of a robot with `dof` joints, in flat-vector order.
    pub fn all(dof: usize, with_beta: bool) -> Vec<Param> {
        let mut v = Vec::with_capacity(PARAMS_PER_JOINT * dof + 12);
        for j in 0..dof {
            v.extend([Param::Theta(j), Param::D(j), Param::A(j), Param::Alpha(j)]);
            if with_beta {
                v.push(Param::Beta(j));
            }
        }
        v.extend((0..6).map(Param::Base));
        v.extend((0..6).map(Param::Tool));
        v
    }

    /// Position of this parameter in the flat vector of a robot with `dof` joints.
    pub fn index(self, dof: usize) -> usize {
        match self {
            Param::Theta(j) => PARAMS_PER_JOINT * j,
            Param::D(j) => PARAMS_PER_JOINT * j + 1,
            Param::A(j) => PARAMS_PER_JOINT * j + 2,
            Param::Alpha(j) => PARAMS_PER_JOINT * j + 3,
            Param::Beta(j) => PARAMS_PER_JOINT * j + 4,
            Param::Base(c) => PARAMS_PER_JOINT * dof + c,
            Param::Tool(c) => PARAMS_PER_JOINT * dof + 6 + c,
            Param::Compliance(j) => PARAMS_PER_JOINT * dof + 12 + j,
            Param::Harmonic(j, k) => PARAMS_PER_JOINT * dof + 12 + dof + HARMONIC_TERMS * j + k,
            Param::Gravity(j, l) => {
                PARAMS_PER_JOINT * dof + 12 + dof + HARMONIC_TERMS * dof + GRAVITY_POINTS * j + l
            }
        }
    }

    /// Whether the parameter is one of the geometry's (a joint's θ, d, a, α, β, the base's
    /// or the tool's), bounded by a robot file's range ([`beyond_range`]); not a compliance,
    /// a harmonic or a gravity term.
    pub fn is_geometric(self) -> bool {
        !matches!(
            self,
            Param::Compliance(_) | Param::Harmonic(..) | Param::Gravity(..)
        )
    }

    /// Whether the parameter is a length (mm); otherwise it is an angle (rad).
    pub fn is_length(self) -> bool {
        match self {
            Param::D(_) | Param::A(_) => true,
            Param::Base(c) | Param::Tool(c) => c < 3,
            _ => false,
        }
    }

    /// The parameter's block for ill-conditioning analysis (Guo 2024 §3.1): `theta`, `d`,
    /// `a`, `alpha`, `beta`, `base` or `tool`.
    pub fn block(self) -> &'static str {
        match self {
            Param::Theta(_) => "theta",
            Param::D(_) => "d",
            Param::A(_) => "a",
            Param::Alpha(_) => "alpha",
            Param::Beta(_) => "beta",
            Param::Base(_) => "base",
            Param::Tool(_) => "tool",
            Param::Compliance(_) => "compliance",
            Param::Harmonic(..) => "harmonics",
            Param::Gravity(..) => "gravity",
        }
    }

    /// Parses a name such as `theta1`, `alpha3`, `base.rz` or `tool.x`.
    pub fn parse(name: &str) -> Option<Param> {
        if let Some(c) = name.strip_prefix("base.") {
            return PART.iter().position(|p| *p == c).map(Param::Base);
        }
        if let Some(c) = name.strip_prefix("tool.") {
            return PART.iter().position(|p| *p == c).map(Param::Tool);
        }
        if name.starts_with('h') {
            return parse_harmonic(name);
        }
        for (l, prefix) in GRAVITY_PREFIX.iter().enumerate() {
            if let Some(num) = name.strip_prefix(prefix) {
                if num.is_empty() || !num.bytes().all(|b| b.is_ascii_digit()) {
                    return None;
                }
                let j: usize = num.parse().ok()?;
                return (j >= 1).then(|| Param::Gravity(j - 1, l));
            }
        }
        // Longest prefixes first: "alpha" before "a".
        let kinds: [Maker; 6] = [
            ("theta", Param::Theta),
            ("alpha", Param::Alpha),
            ("beta", Param::Beta),
            ("a", Param::A),
            ("d", Param::D),
            ("c", Param::Compliance),
        ];
        for (prefix, make) in kinds {
            if let Some(num) = name.strip_prefix(prefix) {
                if num.is_empty() || !num.bytes().all(|b| b.is_ascii_digit()) {
                    return None;
                }
                let j: usize = num.parse().ok()?;
                return if j >= 1 { Some(make(j - 1)) } else { None };
            }
        }
        None
    }

    /// Whether this is a joint compliance ([`Param::Compliance`]).
    pub fn is_compliance(self) -> bool {
        matches!(self, Param::Compliance(_))
    }

    /// The joint (0-based) a geometric joint parameter belongs to (`None` for base, tool and
    /// compliance parameters).
    pub fn joint(self) -> Option<usize> {
        match self {
            Param::Theta(j) | Param::D(j) | Param::A(j) | Param::Alpha(j) | Param::Beta(j) => {
                Some(j)
            }
            Param::Base(_)
            | Param::Tool(_)
            | Param::Compliance(_)
            | Param::Harmonic(..)
            | Param::Gravity(..) => None,
        }
    }
}

/// A parameter's serde form is its name (`theta1`, `base.rz`), as [`Param::parse`] reads it.
impl serde::Serialize for Param {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for Param {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Param, D::Error> {
        let name = String::deserialize(d)?;
        Param::parse(&name)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown parameter \"{name}\"")))
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Param::Theta(j) => write!(f, "theta{}", j + 1),
            Param::D(j) => write!(f, "d{}", j + 1),
            Param::A(j) => write!(f, "a{}", j + 1),
            Param::Alpha(j) => write!(f, "alpha{}", j + 1),
            Param::Beta(j) => write!(f, "beta{}", j + 1),
            Param::Base(c) => write!(f, "base.{}", PART[c]),
            Param::Tool(c) => write!(f, "tool.{}", PART[c]),
            Param::Compliance(j) => write!(f, "c{}", j + 1),
            Param::Harmonic(j, k) => f.write_str(&harmonic_name(j, k)),
            Param::Gravity(j, l) => write!(f, "{}{}", GRAVITY_PREFIX[l], j + 1),
        }
    }
}

/// Joint `j`'s block of `terms` values (`param(j, 0)`, `param(j, 1)`, … stand one after the
/// other) in the flat parameter `values` of a robot with `dof` joints: `None` when the
/// values do not hold it or every one of them is zero. Allocation-free.
#[inline]
pub fn nonzero_block(
    values: &[crate::numeric::Real],
    dof: usize,
    j: usize,
    (terms, param): (usize, fn(usize, usize) -> Param),
) -> Option<&[crate::numeric::Real]> {
    let at = param(j, 0).index(dof);
    let block = values.get(at..at + terms)?;
    block.iter().any(|v| *v != 0.0).then_some(block)
}

/// Adds to each `dv[j]` the offset `offset(j, block)` of joint `j`'s block of `terms`
/// ([`nonzero_block`]; none where it is zero) in the flat parameter `values` of a robot with
/// `dv.len()` joints. Allocation-free.
#[inline]
pub fn add_block_offsets(
    values: &[crate::numeric::Real],
    dv: &mut [crate::numeric::Real],
    terms: (usize, fn(usize, usize) -> Param),
    mut offset: impl FnMut(usize, &[crate::numeric::Real]) -> crate::numeric::Real,
) {
    let dof = dv.len();
    for (j, d) in dv.iter_mut().enumerate() {
        if let Some(block) = nonzero_block(values, dof, j, terms) {
            *d += offset(j, block);
        }
    }
}

/// The refusal of a length (`length`) or an angle beyond a robot file's range for it
/// ([`super::MAX_LENGTH_MM`], [`super::MAX_ANGLE_RAD`]), given as a robot's error (a
/// scenario's, or a method's estimate): the robot's points would not be finite (1e300 mm), or
/// its angles wrap.
pub fn beyond_range(v: crate::numeric::Real, length: bool) -> Option<String> {
    let (most, unit) = match length {
        true => (super::MAX_LENGTH_MM, "mm"),
        false => (super::MAX_ANGLE_RAD, "rad"),
    };
    let shown = crate::error::shown(v);
    (v.abs() > most)
        .then(|| format!("must be within ±{most} {unit} (a robot file's range), got {shown}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for p in Param::all(6, true) {
            assert_eq!(Param::parse(&p.to_string()), Some(p), "{p}");
        }
        assert_eq!(Param::parse("alpha10"), Some(Param::Alpha(9)));
        for j in 0..7 {
            for k in 0..HARMONIC_TERMS {
                let p = Param::Harmonic(j, k);
                assert_eq!(Param::parse(&p.to_string()), Some(p), "{p}");
            }
        }
        assert_eq!(Param::parse("h2c3"), Some(Param::Harmonic(2, 3)));
        assert_eq!(Param::parse("h12s1"), Some(Param::Harmonic(0, 22)));
        assert_eq!(Param::Harmonic(0, 23).to_string(), "h12c1");
        assert_eq!(Param::parse("gt2"), Some(Param::Gravity(1, 2)));
        for l in 0..GRAVITY_POINTS {
            let p = Param::Gravity(6, l);
            assert_eq!(Param::parse(&p.to_string()), Some(p), "{p}");
        }
        for bad in [
            "hs0", "h1s1", "h17s1", "h02s1", "hx1", "h2", "hs", "g1", "ge0",
        ] {
            assert_eq!(Param::parse(bad), None, "{bad}");
        }
        for bad in ["theta0", "theta", "x1", "base.q", "a1b", "d-1", ""] {
            assert_eq!(Param::parse(bad), None, "{bad}");
        }
    }

    #[test]
    fn indices_are_a_bijection() {
        let all = Param::all(4, true);
        let mut idx: Vec<usize> = all.iter().map(|p| p.index(4)).collect();
        idx.sort_unstable();
        assert_eq!(idx, (0..all.len()).collect::<Vec<_>>());
    }
}
