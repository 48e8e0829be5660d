//! Errors of the core. Every variant names the argument it is about, so the binding can
//! turn it into a Python exception whose message a user can act on.

use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    /// A configuration value is wrong (unsorted edges, probability outside [0, 1], ...).
    #[error("{argument}: {message}")]
    InvalidArgument { argument: &'static str, message: String },
    /// An input row holds NaN or infinity where a finite number is needed.
    #[error("{argument}: row {row} is not finite ({message})")]
    NonFinite {
        argument: &'static str,
        row: usize,
        message: String,
    },
    /// Array shapes do not fit together.
    #[error("{argument}: {message}")]
    Shape { argument: &'static str, message: String },
    /// A buffer whose size the argument sets cannot be allocated (or its size overflows).
    #[error("{argument}: needs {bytes} bytes of memory, which cannot be allocated")]
    Memory { argument: &'static str, bytes: u128 },
    /// A covariance the maths needs positive definite is not (Cholesky failed): the binding
    /// raises `ctxmodels.NotPositiveDefiniteError`, so callers need not read the message.
    #[error("{argument}: {message}")]
    NotPositiveDefinite { argument: &'static str, message: String },
    /// An assignment problem has no complete assignment of finite cost: the binding raises
    /// `ctxmodels.InfeasibleAssignmentError`.
    #[error("{argument}: {message}")]
    Infeasible { argument: &'static str, message: String },
    /// A land mask's polygon is not valid land. With `ring` (0 the shell, `k + 1` hole `k`)
    /// the fault is that ring's and `message` says what it is; without, it is the polygon's
    /// and `message` names the rings ("polygon 2 hole 0 lies outside its shell").
    #[error("{argument}: {}", land_text(*.polygon, *.ring, .message))]
    InvalidLand {
        argument: &'static str,
        polygon: usize,
        ring: Option<usize>,
        message: String,
    },
}

/// "shell" or "hole k" for a polygon's ring `ring` (0 the shell, `k + 1` hole `k`).
pub fn ring_name(ring: usize) -> String {
    match ring {
        0 => "shell".to_string(),
        k => format!("hole {}", k - 1),
    }
}

fn land_text(polygon: usize, ring: Option<usize>, message: &str) -> String {
    match ring {
        Some(r) => format!("polygon {polygon} {}: {message}", ring_name(r)),
        None => message.to_string(),
    }
}

impl ModelError {
    pub fn invalid(argument: &'static str, message: impl Into<String>) -> Self {
        ModelError::InvalidArgument {
            argument,
            message: message.into(),
        }
    }

    pub fn shape(argument: &'static str, message: impl Into<String>) -> Self {
        ModelError::Shape {
            argument,
            message: message.into(),
        }
    }

    pub fn non_finite(argument: &'static str, row: usize, message: impl Into<String>) -> Self {
        ModelError::NonFinite {
            argument,
            row,
            message: message.into(),
        }
    }

    pub fn memory(argument: &'static str, bytes: u128) -> Self {
        ModelError::Memory { argument, bytes }
    }

    pub fn not_positive_definite(argument: &'static str, message: impl Into<String>) -> Self {
        ModelError::NotPositiveDefinite {
            argument,
            message: message.into(),
        }
    }

    pub fn infeasible(argument: &'static str, message: impl Into<String>) -> Self {
        ModelError::Infeasible {
            argument,
            message: message.into(),
        }
    }

    /// A fault of polygon `polygon`'s ring `ring` (0 the shell, `k + 1` hole `k`), or of the
    /// whole polygon (`ring` None, `message` naming the rings).
    pub fn invalid_land(
        argument: &'static str,
        polygon: usize,
        ring: Option<usize>,
        message: impl Into<String>,
    ) -> Self {
        ModelError::InvalidLand {
            argument,
            polygon,
            ring,
            message: message.into(),
        }
    }

    /// The argument the error is about.
    pub fn argument(&self) -> &'static str {
        match self {
            ModelError::InvalidArgument { argument, .. }
            | ModelError::NonFinite { argument, .. }
            | ModelError::Shape { argument, .. }
            | ModelError::Memory { argument, .. }
            | ModelError::NotPositiveDefinite { argument, .. }
            | ModelError::Infeasible { argument, .. }
            | ModelError::InvalidLand { argument, .. } => argument,
        }
    }
}

pub type Result<T> = std::result::Result<T, ModelError>;

/// Checks that `value` is a finite probability.
pub(crate) fn check_probability(argument: &'static str, value: f64) -> Result<()> {
    if !(0.0..=1.0).contains(&value) {
        return Err(ModelError::invalid(
            argument,
            format!("must be a probability in [0, 1], got {value}"),
        ));
    }
    Ok(())
}
