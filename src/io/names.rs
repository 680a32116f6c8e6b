//! The names of the library's choices as command lines, scripts and settings files write them:
//! one [`FromStr`] per choice that accepts exactly the name its `Display` prints, and the
//! [`Choice`] trait that lists the names with a one-line help each (the command line builds
//! its `--metric`, `--loss`, `--certify`, `--format`, `--weights` and `--init-method` parsers
//! from it, so the library enums are the only definition of these vocabularies).
//!
//! | type | names |
//! |---|---|
//! | [`Metric`] | `chordal`, `quaternion`, `geodesic` |
//! | [`LossKind`] (a [`Loss`] without its threshold) | `l2`, `l1`, `huber`, `cauchy` |
//! | [`MultipleLoss`] (the objectives of `rotavg multiple --loss`) | `auto`, `chordal`, `geodesic`, `l1`, `huber`, `cauchy` |
//! | [`CertifyMode`] | `auto`, `theory`, `dual`, `sdp`, `staircase`, `none` |
//! | [`GraphFormat`] | `auto`, `g2o`, `1dsfm`, `json`, `colmap` |
//! | [`OutputFormat`] | `auto`, `json`, `g2o`, `colmap` |
//! | [`ConjugateFormat`] | `auto`, `json`, `tabb`, `eth` |
//! | [`QuaternionOrder`] (pose streams) | `xyzw`, `wxyz` |
//! | [`WeightSource`] | `file`, `unit` |
//! | [`Initialisation`] (the named ones) | `spectral`, `tree` |
//!
//! The `FromStr` impls of types defined in other modules live here, beside the others, so
//! that the vocabulary is in one place.
//!
//! ```
//! use rotavg::io::names::{Choice, LossKind, MultipleLoss};
//! use rotavg::certify::CertifyMode;
//! use rotavg::{Loss, Metric, Objective};
//! assert_eq!("geodesic".parse::<Metric>()?, Metric::Geodesic);
//! assert_eq!("staircase".parse::<CertifyMode>()?, CertifyMode::Staircase);
//! assert_eq!("huber".parse::<LossKind>()?.with_threshold_deg(3.0), Loss::Huber { threshold_deg: 3.0 });
//! // `rotavg multiple --loss l1` is the geodesic L1 objective.
//! let l1 = "l1".parse::<MultipleLoss>()?.objective(5.0);
//! assert_eq!(l1, Objective::new(Metric::Geodesic, Loss::L1));
//! assert_eq!(MultipleLoss::name_of(&l1), "l1");
//! // Unknown names are an error that lists the known ones.
//! let e = "euclid".parse::<Metric>().unwrap_err();
//! assert!(e.to_string().contains("chordal, quaternion, geodesic"));
//! assert_eq!(Metric::choices().len(), 3);
//! # Ok::<(), rotavg::Error>(())
//! ```

use crate::certify::CertifyMode;
use crate::error::{Error, Result};
use crate::io::detect::{GraphFormat, WeightSource};
use crate::io::handeye::QuaternionOrder;
use crate::io::output::OutputFormat;
use crate::multiple::Initialisation;
use crate::objective::{Loss, Objective};
use crate::so3::Metric;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// A value chosen by name: its name, a one-line help, and the list of values that have names.
///
/// ```
/// use rotavg::io::names::Choice;
/// use rotavg::io::detect::GraphFormat;
/// let names: Vec<&str> = GraphFormat::choices().iter().map(|f| f.name()).collect();
/// assert_eq!(names, ["auto", "g2o", "1dsfm", "json", "colmap"]);
/// assert_eq!(GraphFormat::from_name("1dsfm"), Some(GraphFormat::OneDsfm));
/// assert!(!GraphFormat::Json.help().is_empty());
/// ```
pub trait Choice: Sized + Clone + Send + Sync + 'static {
    /// Every value that has a name, in the order a help text lists them.
    fn choices() -> Vec<Self>;
    /// The name (what `Display` prints and `FromStr` reads).
    fn name(&self) -> &'static str;
    /// One line saying what the value means.
    fn help(&self) -> &'static str;
    /// The value of a name (exact match), if any.
    fn from_name(name: &str) -> Option<Self> {
        Self::choices().into_iter().find(|c| c.name() == name)
    }
}

/// Parse `s` as a `T` by name; [`Error::InvalidSettings`] naming `what` and the known names.
fn parse_choice<T: Choice>(s: &str, what: &str) -> Result<T> {
    T::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = T::choices().iter().map(Choice::name).collect();
        Error::InvalidSettings {
            name: what.into(),
            reason: format!("unknown name `{s}` (expected one of {})", names.join(", ")),
        }
    })
}

impl Choice for Metric {
    fn choices() -> Vec<Self> {
        vec![Metric::Chordal, Metric::Quaternion, Metric::Geodesic]
    }
    fn name(&self) -> &'static str {
        match self {
            Metric::Chordal => "chordal",
            Metric::Quaternion => "quaternion",
            Metric::Geodesic => "geodesic",
        }
    }
    fn help(&self) -> &'static str {
        match self {
            Metric::Chordal => "Chordal distance ||R - S||_F",
            Metric::Quaternion => "Quaternion distance 2 sin(theta / 4)",
            Metric::Geodesic => "Angle (geodesic) distance theta",
        }
    }
}

impl FromStr for Metric {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_choice(s, "metric")
    }
}

impl Choice for CertifyMode {
    fn choices() -> Vec<Self> {
        vec![
            CertifyMode::Auto,
            CertifyMode::Theory,
            CertifyMode::Dual,
            CertifyMode::Sdp,
            CertifyMode::Staircase,
            CertifyMode::BranchAndBound,
            CertifyMode::None,
        ]
    }
    fn name(&self) -> &'static str {
        CertifyMode::name(*self)
    }
    fn help(&self) -> &'static str {
        match self {
            CertifyMode::Auto => {
                "The best method for the problem (single: theory, then branch and bound; multiple: dual, then SDP on small graphs or staircase on large ones; conjugate: SDP for chordal L2, then branch and bound)"
            }
            CertifyMode::Theory => "Theorems: closed forms and convexity balls (single averaging)",
            CertifyMode::Dual => "Dual certificate only (multiple averaging)",
            CertifyMode::Sdp => "The SDP relaxation (multiple: after a failed dual certificate)",
            CertifyMode::Staircase => "Dual, then the Riemannian staircase (multiple averaging)",
            CertifyMode::BranchAndBound => {
                "Branch and bound over SO(3) (single and conjugate averaging, every cost)"
            }
            CertifyMode::None => "No certificate",
        }
    }
}

impl FromStr for CertifyMode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_choice(s, "certify.mode")
    }
}

impl Choice for GraphFormat {
    fn choices() -> Vec<Self> {
        vec![
            GraphFormat::Auto,
            GraphFormat::G2o,
            GraphFormat::OneDsfm,
            GraphFormat::Json,
            GraphFormat::Colmap,
        ]
    }
    fn name(&self) -> &'static str {
        match self {
            GraphFormat::Auto => "auto",
            GraphFormat::G2o => "g2o",
            GraphFormat::OneDsfm => "1dsfm",
            GraphFormat::Json => "json",
            GraphFormat::Colmap => "colmap",
        }
    }
    fn help(&self) -> &'static str {
        match self {
            GraphFormat::Auto => "From the extension, then the content",
            GraphFormat::G2o => "g2o / TORO pose graph",
            GraphFormat::OneDsfm => "1DSfM EGs.txt",
            GraphFormat::Json => "JSON problem (contract section 5)",
            GraphFormat::Colmap => {
                "COLMAP database (SQLite; a database.db file or the folder holding it)"
            }
        }
    }
}

impl Choice for WeightSource {
    fn choices() -> Vec<Self> {
        vec![WeightSource::File, WeightSource::Unit]
    }
    fn name(&self) -> &'static str {
        match self {
            WeightSource::File => "file",
            WeightSource::Unit => "unit",
        }
    }
    fn help(&self) -> &'static str {
        match self {
            WeightSource::File => {
                "Weights from the file where the format has them (g2o: SE-Sync's kappa)"
            }
            WeightSource::Unit => "All weights 1",
        }
    }
}

impl fmt::Display for WeightSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for WeightSource {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_choice(s, "weights")
    }
}

impl Choice for Initialisation {
    fn choices() -> Vec<Self> {
        vec![Initialisation::Spectral, Initialisation::SpanningTree]
    }
    fn name(&self) -> &'static str {
        match self {
            Initialisation::Spectral => "spectral",
            Initialisation::SpanningTree => "tree",
            Initialisation::Given(_) => "given",
            Initialisation::L1Start(_) => "l1-start",
        }
    }
    fn help(&self) -> &'static str {
        match self {
            Initialisation::Spectral => "Spectral (connection Laplacian eigenvectors)",
            Initialisation::SpanningTree => "Maximum-weight spanning tree",
            Initialisation::Given(_) => "A given estimate",
            Initialisation::L1Start(_) => "The L1 start, already solved",
        }
    }
}

impl fmt::Display for Initialisation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Initialisation {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_choice(s, "init")
    }
}

/// A [`Loss`] without its threshold: what `--loss` names; the threshold comes separately
/// ([`LossKind::with_threshold_deg`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LossKind {
    /// Squared distance.
    #[default]
    L2,
    /// Absolute distance.
    L1,
    /// Huber.
    Huber,
    /// Cauchy.
    Cauchy,
}

impl LossKind {
    /// The loss, with `threshold_deg` as the Huber threshold or Cauchy scale (a residual angle
    /// in degrees; unused by `l2` and `l1`).
    ///
    /// ```
    /// use rotavg::io::names::LossKind;
    /// use rotavg::Loss;
    /// assert_eq!(LossKind::Cauchy.with_threshold_deg(2.0), Loss::Cauchy { scale_deg: 2.0 });
    /// assert_eq!(LossKind::L1.with_threshold_deg(2.0), Loss::L1);
    /// ```
    pub fn with_threshold_deg(self, threshold_deg: f64) -> Loss {
        match self {
            LossKind::L2 => Loss::L2,
            LossKind::L1 => Loss::L1,
            LossKind::Huber => Loss::Huber { threshold_deg },
            LossKind::Cauchy => Loss::Cauchy {
                scale_deg: threshold_deg,
            },
        }
    }

    /// The kind of a loss.
    pub fn of(loss: &Loss) -> LossKind {
        match loss {
            Loss::L2 => LossKind::L2,
            Loss::L1 => LossKind::L1,
            Loss::Huber { .. } => LossKind::Huber,
            Loss::Cauchy { .. } => LossKind::Cauchy,
        }
    }
}

impl Choice for LossKind {
    fn choices() -> Vec<Self> {
        vec![
            LossKind::L2,
            LossKind::L1,
            LossKind::Huber,
            LossKind::Cauchy,
        ]
    }
    fn name(&self) -> &'static str {
        match self {
            LossKind::L2 => "l2",
            LossKind::L1 => "l1",
            LossKind::Huber => "huber",
            LossKind::Cauchy => "cauchy",
        }
    }
    fn help(&self) -> &'static str {
        match self {
            LossKind::L2 => "Squared distance",
            LossKind::L1 => "Absolute distance",
            LossKind::Huber => "Huber: quadratic up to the threshold angle, linear beyond",
            LossKind::Cauchy => "Cauchy with the threshold angle as scale",
        }
    }
}

impl fmt::Display for LossKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for LossKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_choice(s, "loss")
    }
}

/// The objectives of multiple averaging by one name, as `rotavg multiple --loss` takes them
/// (and as its `--json` output reports them in `loss`): chordal L2 or a loss of the residual
/// angle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MultipleLoss {
    /// The data decide (the default): chordal L2, unless its residuals show outliers; then
    /// Cauchy, with its inlier graph certified ([`MultipleLoss::robust_on_outliers`]).
    #[default]
    Auto,
    /// Chordal L2 (certifiable).
    Chordal,
    /// Geodesic L2.
    Geodesic,
    /// Geodesic L1.
    L1,
    /// Huber on the residual angle.
    Huber,
    /// Cauchy on the residual angle.
    Cauchy,
}

impl MultipleLoss {
    /// The options of `rotavg multiple` that only a robust loss takes (`given`: each flag's
    /// name and whether it was given) are an error with another loss; `--inlier-output` needs
    /// the inlier graph certified (`certify_none`: `--certify none` was given).
    pub fn check_robust_flags(self, given: &[(&str, bool)], certify_none: bool) -> Result<()> {
        let robust = !matches!(self, MultipleLoss::Chordal | MultipleLoss::Geodesic);
        let inlier_output = given.iter().any(|&(f, g)| g && f == "--inlier-output");
        let (name, reason) = match given.iter().find(|(_, given)| *given) {
            Some((flag, _)) if !robust => (
                *flag,
                format!("needs a robust loss (--loss l1, huber or cauchy), not {self}"),
            ),
            _ if inlier_output && certify_none => (
                "--inlier-output",
                "the inlier graph is refined only when it is certified (not with --certify none)"
                    .into(),
            ),
            _ => return Ok(()),
        };
        Err(Error::InvalidSettings {
            name: name.to_string(),
            reason,
        })
    }

    /// Gravity priors take the chordal L2 loss (with `auto`, least squares or the robust one
    /// the residuals call for) and the robust losses; the geodesic L2 loss is an error.
    pub fn check_gravity(self) -> Result<()> {
        if self != MultipleLoss::Geodesic {
            return Ok(());
        }
        Err(Error::InvalidSettings {
            name: "--gravity".into(),
            reason: "gravity priors are solved with the chordal L2 loss or a robust loss (l1, \
                     huber, cauchy), not `--loss geodesic`"
                .into(),
        })
    }

    /// The objective, with `threshold_deg` as the Huber threshold or Cauchy scale (degrees).
    ///
    /// ```
    /// use rotavg::io::names::MultipleLoss;
    /// use rotavg::{Loss, Metric, Objective};
    /// assert_eq!(MultipleLoss::Chordal.objective(5.0), Objective::CHORDAL_L2);
    /// assert_eq!(
    ///     MultipleLoss::Huber.objective(2.0),
    ///     Objective::new(Metric::Geodesic, Loss::Huber { threshold_deg: 2.0 })
    /// );
    /// ```
    pub fn objective(self, threshold_deg: f64) -> Objective {
        let geodesic = |kind: LossKind| {
            Objective::new(Metric::Geodesic, kind.with_threshold_deg(threshold_deg))
        };
        match self {
            MultipleLoss::Auto | MultipleLoss::Chordal => Objective::CHORDAL_L2,
            MultipleLoss::Geodesic => geodesic(LossKind::L2),
            MultipleLoss::L1 => geodesic(LossKind::L1),
            MultipleLoss::Huber => geodesic(LossKind::Huber),
            MultipleLoss::Cauchy => geodesic(LossKind::Cauchy),
        }
    }

    /// The inlier threshold (degrees) of a robust loss: `given` (`--inlier-threshold`), or for
    /// L1 `threshold_deg` (`--loss-threshold`) when none is given; none for least squares.
    ///
    /// ```
    /// use rotavg::io::names::MultipleLoss;
    /// assert_eq!(MultipleLoss::L1.inlier_threshold_deg(5.0, None), Some(5.0));
    /// assert_eq!(MultipleLoss::Huber.inlier_threshold_deg(5.0, None), None);
    /// assert_eq!(MultipleLoss::Cauchy.inlier_threshold_deg(5.0, Some(2.0)), Some(2.0));
    /// assert_eq!(MultipleLoss::Chordal.inlier_threshold_deg(5.0, Some(2.0)), None);
    /// ```
    pub fn inlier_threshold_deg(self, threshold_deg: f64, given: Option<f64>) -> Option<f64> {
        match self {
            MultipleLoss::L1 => Some(given.unwrap_or(threshold_deg)),
            MultipleLoss::Auto | MultipleLoss::Huber | MultipleLoss::Cauchy => given,
            MultipleLoss::Chordal | MultipleLoss::Geodesic => None,
        }
    }

    /// The inlier threshold (degrees) with which `rotavg certify --loss` judges an estimate:
    /// `None` for `chordal` (all edges only); for `l1`, `huber`, `cauchy` `given`
    /// (`--inlier-threshold`) or else `threshold_deg` (`--loss-threshold`), which must be
    /// positive and finite. `auto` and `geodesic` are refused ([`Error::InvalidSettings`],
    /// field `loss`): an estimate is judged on all edges or on an inlier set.
    ///
    /// ```
    /// use rotavg::io::names::MultipleLoss;
    /// assert_eq!(MultipleLoss::Chordal.certify_inlier_threshold_deg(5.0, None)?, None);
    /// assert_eq!(MultipleLoss::Huber.certify_inlier_threshold_deg(5.0, None)?, Some(5.0));
    /// assert_eq!(MultipleLoss::L1.certify_inlier_threshold_deg(5.0, Some(2.0))?, Some(2.0));
    /// assert!(MultipleLoss::Auto.certify_inlier_threshold_deg(5.0, None).is_err());
    /// assert!(MultipleLoss::Cauchy.certify_inlier_threshold_deg(5.0, Some(0.0)).is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn certify_inlier_threshold_deg(
        self,
        threshold_deg: f64,
        given: Option<f64>,
    ) -> Result<Option<f64>> {
        match self {
            MultipleLoss::Chordal => Ok(None),
            MultipleLoss::L1 | MultipleLoss::Huber | MultipleLoss::Cauchy => {
                let t = given.unwrap_or(threshold_deg);
                crate::validate::positive("inlier_threshold", t)?;
                Ok(Some(t))
            }
            MultipleLoss::Auto | MultipleLoss::Geodesic => Err(Error::InvalidSettings {
                name: "loss".into(),
                reason: format!(
                    "certify judges an estimate on all edges (chordal) or on a robust loss's \
                     inlier set (l1, huber, cauchy), not with {self}"
                ),
            }),
        }
    }

    /// The robust objective `auto` switches to when the least-squares residuals show outliers
    /// ([`MultipleSettings::robust_on_outliers`](crate::multiple::MultipleSettings::robust_on_outliers)):
    /// Cauchy with scale `threshold_deg`; none for the other names (their loss is fixed).
    ///
    /// ```
    /// use rotavg::io::names::MultipleLoss;
    /// use rotavg::{Loss, Metric, Objective};
    /// assert_eq!(MultipleLoss::Auto.objective(5.0), Objective::CHORDAL_L2); // solved first
    /// assert_eq!(
    ///     MultipleLoss::Auto.robust_on_outliers(5.0),
    ///     Some(Objective::new(Metric::Geodesic, Loss::Cauchy { scale_deg: 5.0 }))
    /// );
    /// assert_eq!(MultipleLoss::Chordal.robust_on_outliers(5.0), None);
    /// ```
    pub fn robust_on_outliers(self, threshold_deg: f64) -> Option<Objective> {
        (self == MultipleLoss::Auto).then(|| MultipleLoss::Cauchy.objective(threshold_deg))
    }

    /// The name of an objective in this vocabulary (`chordal`, `geodesic`, `l1`, `huber`,
    /// `cauchy`), or `metric loss` (e.g. `chordal l1`) for one outside it.
    pub fn name_of(objective: &Objective) -> String {
        let named = match (objective.metric, LossKind::of(&objective.loss)) {
            (Metric::Chordal, LossKind::L2) => Some(MultipleLoss::Chordal),
            (Metric::Geodesic, LossKind::L2) => Some(MultipleLoss::Geodesic),
            (Metric::Geodesic, LossKind::L1) => Some(MultipleLoss::L1),
            (Metric::Geodesic, LossKind::Huber) => Some(MultipleLoss::Huber),
            (Metric::Geodesic, LossKind::Cauchy) => Some(MultipleLoss::Cauchy),
            _ => None,
        };
        match named {
            Some(m) => m.name().to_string(),
            None => format!("{} {}", objective.metric, objective.loss.name()),
        }
    }
}

impl Choice for MultipleLoss {
    fn choices() -> Vec<Self> {
        vec![
            MultipleLoss::Auto,
            MultipleLoss::Chordal,
            MultipleLoss::Geodesic,
            MultipleLoss::L1,
            MultipleLoss::Huber,
            MultipleLoss::Cauchy,
        ]
    }
    fn name(&self) -> &'static str {
        match self {
            MultipleLoss::Auto => "auto",
            MultipleLoss::Chordal => "chordal",
            MultipleLoss::Geodesic => "geodesic",
            MultipleLoss::L1 => "l1",
            MultipleLoss::Huber => "huber",
            MultipleLoss::Cauchy => "cauchy",
        }
    }
    fn help(&self) -> &'static str {
        match self {
            MultipleLoss::Auto => {
                "Chordal L2, unless its residuals show outliers: then cauchy, and its inlier \
                 graph's chordal L2 problem certified"
            }
            MultipleLoss::Chordal => "Chordal L2 (certifiable)",
            MultipleLoss::Geodesic => "Geodesic L2",
            MultipleLoss::L1 => "Geodesic L1",
            MultipleLoss::Huber => "Huber on the residual angle (threshold --loss-threshold)",
            MultipleLoss::Cauchy => "Cauchy on the residual angle (scale --loss-threshold)",
        }
    }
}

impl fmt::Display for MultipleLoss {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for MultipleLoss {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_choice(s, "loss")
    }
}

/// The input formats of conjugate (hand-eye) problems.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConjugateFormat {
    /// A directory with `robot_cali.txt` is Tabb, another directory ETH, anything else JSON.
    #[default]
    Auto,
    /// `{"pairs": [{"left": L, "right": R, "weight": w}]}` (contract section 5).
    Json,
    /// Tabb dataset directory (`robot_cali.txt`, `cali.txt`): relative motions of all station
    /// pairs ([`crate::io::handeye::read_tabb_dir`]).
    Tabb,
    /// ETH ASL directory with a hand CSV and a camera CSV
    /// ([`crate::io::handeye::read_eth_dir`]).
    Eth,
}

impl Choice for ConjugateFormat {
    fn choices() -> Vec<Self> {
        vec![
            ConjugateFormat::Auto,
            ConjugateFormat::Json,
            ConjugateFormat::Tabb,
            ConjugateFormat::Eth,
        ]
    }
    fn name(&self) -> &'static str {
        match self {
            ConjugateFormat::Auto => "auto",
            ConjugateFormat::Json => "json",
            ConjugateFormat::Tabb => "tabb",
            ConjugateFormat::Eth => "eth",
        }
    }
    fn help(&self) -> &'static str {
        match self {
            ConjugateFormat::Auto => {
                "Directory with robot_cali.txt + cali.txt is Tabb, a directory of CSVs is ETH, anything else JSON"
            }
            ConjugateFormat::Json => {
                "{\"pairs\": [{\"left\": L, \"right\": R, \"weight\": w}]} (contract section 5)"
            }
            ConjugateFormat::Tabb => {
                "Tabb dataset directory (robot_cali.txt, cali.txt): relative motions of all station pairs"
            }
            ConjugateFormat::Eth => {
                "Pose streams (ETH ASL, Vicon, ...): a directory with a hand CSV (*base_link*, *hand*, *vicon*) and a camera CSV (*target*, *camera*), or --hand and --camera"
            }
        }
    }
}

impl fmt::Display for ConjugateFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ConjugateFormat {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_choice(s, "format")
    }
}

impl Choice for OutputFormat {
    fn choices() -> Vec<Self> {
        vec![
            OutputFormat::Auto,
            OutputFormat::Json,
            OutputFormat::G2o,
            OutputFormat::Colmap,
        ]
    }
    fn name(&self) -> &'static str {
        match self {
            OutputFormat::Auto => "auto",
            OutputFormat::Json => "json",
            OutputFormat::G2o => "g2o",
            OutputFormat::Colmap => "colmap",
        }
    }
    fn help(&self) -> &'static str {
        match self {
            OutputFormat::Auto => {
                "From the path: *.g2o is g2o, a folder (ending in /) or *images.txt a COLMAP model, anything else JSON"
            }
            OutputFormat::Json => "{\"node_ids\": [...], \"rotations\": [R, ...]}",
            OutputFormat::G2o => "g2o: the edges and the estimate as vertex lines",
            OutputFormat::Colmap => {
                "COLMAP sparse model (a folder or images.txt): world-to-camera quaternions, zero translations, image names"
            }
        }
    }
}

impl fmt::Display for OutputFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for OutputFormat {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_choice(s, "output_format")
    }
}

impl Choice for QuaternionOrder {
    fn choices() -> Vec<Self> {
        vec![QuaternionOrder::Xyzw, QuaternionOrder::Wxyz]
    }
    fn name(&self) -> &'static str {
        match self {
            QuaternionOrder::Xyzw => "xyzw",
            QuaternionOrder::Wxyz => "wxyz",
        }
    }
    fn help(&self) -> &'static str {
        match self {
            QuaternionOrder::Xyzw => "qx qy qz qw: scalar last (ETH ASL, ROS)",
            QuaternionOrder::Wxyz => "qw qx qy qz: scalar first",
        }
    }
}

impl fmt::Display for QuaternionOrder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for QuaternionOrder {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_choice(s, "quaternion order")
    }
}
