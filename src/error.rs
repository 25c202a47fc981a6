//! The one error type of the core. Every variant names the argument it is
//! about and, where there is one, the offending index and value, so that the
//! binding layer can pass the `Display` text to Python unchanged.

use std::path::PathBuf;

/// Everything that can go wrong in mcsample's core.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A table weight that is NaN, infinite or negative.
    #[error("{arg}{index} = {value}: {arg} must be finite and >= 0")]
    InvalidWeight {
        /// Name of the argument.
        arg: &'static str,
        /// Index of the first offending entry, formatted as `[i]` or `[i, j]`.
        index: String,
        /// The offending value.
        value: f64,
    },
    /// A table whose weights are all zero (or that is empty).
    #[error("{arg} is empty or all zero: nothing to sample")]
    AllZero {
        /// Name of the argument.
        arg: &'static str,
    },
    /// An array of the wrong shape.
    #[error("{arg} must have shape {expected}, got {got}")]
    Shape {
        /// Name of the argument.
        arg: &'static str,
        /// The shapes accepted, e.g. `(N, 2) or (2,)`.
        expected: String,
        /// The shape given, e.g. `(5, 3)`.
        got: String,
    },
    /// A scalar parameter outside its valid range.
    #[error("{arg} = {value}: {requirement}")]
    Parameter {
        /// Name of the argument.
        arg: &'static str,
        /// The offending value.
        value: f64,
        /// What the value must satisfy, e.g. `must be >= 0`.
        requirement: &'static str,
    },
    /// A choice among named options that is unknown or does not fit the
    /// other arguments.
    #[error("{arg} = {value:?}: {requirement}")]
    Choice {
        /// Name of the argument.
        arg: &'static str,
        /// The value given.
        value: String,
        /// What it must be.
        requirement: String,
    },
    /// An entry of a batch outside its valid range (e.g. `u` outside `[0, 1]`).
    #[error("{arg}{index} = {value}: {requirement}")]
    Element {
        /// Name of the argument.
        arg: &'static str,
        /// Index of the first offending entry, formatted as `[i]` or `[i, j]`.
        index: String,
        /// The offending value.
        value: f64,
        /// What every entry must satisfy.
        requirement: String,
    },
    /// An integer argument that is negative or too large.
    #[error("{arg} = {value}: {requirement}")]
    Integer {
        /// Name of the argument.
        arg: &'static str,
        /// The offending value, as text (it may not fit any Rust integer).
        value: String,
        /// What the value must satisfy.
        requirement: String,
    },
    /// An index outside its table.
    #[error("{arg}{index} = {value}: must be an index in [0, {len})")]
    Index {
        /// Name of the argument.
        arg: &'static str,
        /// Position of the first offending entry, formatted as `[i]` or `[i, j]`.
        index: String,
        /// The offending index.
        value: i64,
        /// The table's length along that axis.
        len: usize,
    },
    /// A Phong material that reflects more than it receives.
    #[error("diffuse[{channel}] + specular[{channel}] = {sum}: must be <= 1 (energy conservation)")]
    NotEnergyConserving {
        /// The RGB channel (0, 1, 2).
        channel: usize,
        /// ρd + ρs in that channel.
        sum: f64,
    },
    /// A table too large for 32-bit indices.
    #[error("{arg} has {len} entries: at most {max} are supported")]
    TooLarge {
        /// Name of the argument.
        arg: &'static str,
        /// Number of entries given.
        len: usize,
        /// The largest number accepted.
        max: usize,
    },
    /// An argument that is missing, or that does not fit the others or the
    /// way it is used: a scene without a sensor, a second environment
    /// emitter, a read-only or non-contiguous `out` array.
    #[error("{message}")]
    Argument {
        /// Name of the argument.
        arg: &'static str,
        /// The whole message, naming the argument and what to do.
        message: String,
    },
    /// Two batches whose row counts differ, neither being a single row (one
    /// row is used for every row of the other).
    #[error(
        "{arg_a} has {rows_a} row{s_a} and {arg_b} has {rows_b}: give both as many rows, \
         or one of them as a single row (used for every row of the other)",
        s_a = plural(.rows_a)
    )]
    Rows {
        /// Name of the first argument.
        arg_a: &'static str,
        /// Its number of rows.
        rows_a: usize,
        /// Name of the second argument.
        arg_b: &'static str,
        /// Its number of rows.
        rows_b: usize,
    },
    /// The worker threads could not be started.
    #[error("cannot start {threads} worker threads: {message}")]
    ThreadPool {
        /// The number of threads asked for.
        threads: usize,
        /// The system's reason.
        message: String,
    },
    /// Memory that cannot be had (Python's `MemoryError`).
    #[error(
        "not enough memory for {what}: {bytes} bytes ({gib:.2} GiB) were asked for",
        gib = *.bytes as f64 / (1u64 << 30) as f64
    )]
    Memory {
        /// What the memory was for, e.g. `the film`.
        what: &'static str,
        /// How many bytes were asked for.
        bytes: u128,
    },
    /// A file that cannot be read or written, or whose content is invalid.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

/// Checks a count of `len` entries of `arg` against the most supported.
///
/// # Errors
/// [`Error::TooLarge`] when `len > max`.
pub fn check_at_most(arg: &'static str, len: usize, max: usize) -> Result<()> {
    if len > max {
        return Err(Error::TooLarge { arg, len, max });
    }
    Ok(())
}

/// Checks a scalar parameter: `ok` says whether `value` of `arg` is
/// valid.
///
/// # Errors
/// [`Error::Parameter`] stating `requirement` when `ok` is false.
pub fn check_parameter(
    arg: &'static str,
    value: f64,
    ok: bool,
    requirement: &'static str,
) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::Parameter {
            arg,
            value,
            requirement,
        })
    }
}

/// The plural ending of a count of `n`.
fn plural(n: &usize) -> &'static str {
    if *n == 1 { "" } else { "s" }
}

/// Result type of the core.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Formats a shape as numpy prints it: `(5, 3)`, `(2,)`, `()`.
pub fn shape_str(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => {
            let parts: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
            format!("({})", parts.join(", "))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_argument_index_and_value() {
        let e = Error::InvalidWeight {
            arg: "weights",
            index: "[17]".into(),
            value: -0.5,
        };
        assert_eq!(
            e.to_string(),
            "weights[17] = -0.5: weights must be finite and >= 0"
        );
        let e = Error::Element {
            arg: "u",
            index: "[3, 1]".into(),
            value: f64::NAN,
            requirement: "must lie in [0, 1]".into(),
        };
        assert_eq!(e.to_string(), "u[3, 1] = NaN: must lie in [0, 1]");
        let e = Error::Rows {
            arg_a: "wi",
            rows_a: 2,
            arg_b: "wo",
            rows_b: 3,
        };
        assert!(e.to_string().starts_with("wi has 2 rows and wo has 3: "));
    }

    #[test]
    fn shapes_print_like_numpy() {
        assert_eq!(shape_str(&[5, 3]), "(5, 3)");
        assert_eq!(shape_str(&[2]), "(2,)");
        assert_eq!(shape_str(&[]), "()");
    }
}
