//! Scalar arguments, parsed one way by every binding: integers in a range
//! ([`index_arg`]), path depths ([`depth_arg`]), seeds ([`seed_arg`]) and
//! named options ([`choice`]). A value out of range raises ValueError naming
//! the argument (never OverflowError, however large the int); a value of
//! the wrong type raises TypeError.

use crate::error::Error;
use crate::mis::Heuristic;
use crate::python::Obj;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

/// `ob` as a Python int (anything with `__index__`, as numpy integers),
/// else TypeError naming `arg`.
fn int_arg<'py>(ob: &Obj<'py>, arg: &str) -> PyResult<Obj<'py>> {
    let py = ob.py();
    py.import(pyo3::intern!(py, "operator"))?
        .call_method1(pyo3::intern!(py, "index"), (ob,))
        .map_err(|_| {
            PyTypeError::new_err(format!("{arg} must be an integer, got {}", type_name(ob)))
        })
}

/// Three numbers: a sequence of three floats for `arg`, or, when `grey`,
/// also one float for all three (an RGB value). A wrong type is a
/// TypeError, a wrong length a ValueError, both naming `arg`.
pub fn three_floats(ob: &Obj<'_>, arg: &'static str, grey: bool) -> PyResult<[f64; 3]> {
    if grey && let Ok(v) = ob.extract::<f64>() {
        return Ok([v; 3]);
    }
    let (what, expected) = if grey {
        ("a number or three numbers (RGB)", "(3,) or a number")
    } else {
        ("three numbers", "(3,)")
    };
    let values: Vec<f64> = ob
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("{arg} must be {what}")))?;
    values.try_into().map_err(|v: Vec<f64>| {
        Error::Shape {
            arg,
            expected: expected.into(),
            got: format!("({},)", v.len()),
        }
        .into()
    })
}

/// The name of `ob`'s type, for messages.
pub fn type_name(ob: &Obj<'_>) -> String {
    ob.get_type()
        .name()
        .map_or_else(|_| "?".into(), |n| n.to_string())
}

/// An integer argument in `[min, max]`; values outside (however large)
/// raise ValueError (never OverflowError), non-integers TypeError.
pub fn index_arg(ob: &Obj<'_>, arg: &'static str, min: u64, max: u64) -> PyResult<u64> {
    let int = int_arg(ob, arg)?;
    if int.lt(min)? || int.gt(max)? {
        return Err(Error::Integer {
            arg,
            value: int.to_string(),
            requirement: format!("must be an integer from {min} to {max}"),
        }
        .into());
    }
    int.extract()
}

/// A path depth such as `max_depth`: -1 for unbounded (`None`), else an
/// integer from 0 to `u32::MAX`; anything else (of any size) raises
/// ValueError naming `arg`, a non-integer TypeError.
pub fn depth_arg(ob: &Obj<'_>, arg: &'static str) -> PyResult<Option<u32>> {
    let int = int_arg(ob, arg)?;
    if int.eq(-1)? {
        return Ok(None);
    }
    if int.lt(0)? || int.gt(u32::MAX)? {
        return Err(Error::Integer {
            arg,
            value: int.to_string(),
            requirement: format!(
                "must be -1 (unbounded) or an integer from 0 to {}",
                u32::MAX
            ),
        }
        .into());
    }
    Ok(Some(int.extract()?))
}

/// The 64-bit seed that `ob` stands for, by `mcsample.seeds.resolve_seed`
/// (the one definition): an int in `[0, 2⁶⁴)` as it is, None fresh entropy
/// from the operating system, a `numpy.random.Generator` a seed drawn from
/// it; anything else TypeError, an int out of range ValueError naming `arg`.
pub fn seed_arg(ob: &Obj<'_>, arg: &str) -> PyResult<u64> {
    let py = ob.py();
    py.import(pyo3::intern!(py, "mcsample.seeds"))?
        .getattr(pyo3::intern!(py, "resolve_seed"))?
        .call1((ob, arg))?
        .extract()
}

/// [`seed_arg`] for an argument named `seed`, as pyo3's `from_py_with`
/// takes it (so that the signature can show the default `seed=0`).
pub fn seed(ob: &Obj<'_>) -> PyResult<u64> {
    seed_arg(ob, "seed")
}

/// The option called `value` among the named `options` of argument `arg`;
/// else ValueError listing the names (an alias, a later name for the value
/// of an earlier one, is accepted but not listed).
pub fn choice<T: Copy + PartialEq>(
    arg: &'static str,
    value: &str,
    options: &[(&str, T)],
) -> PyResult<T> {
    if let Some(&(_, option)) = options.iter().find(|(name, _)| *name == value) {
        return Ok(option);
    }
    let names: Vec<String> = options
        .iter()
        .enumerate()
        .filter(|&(i, (_, option))| !options[..i].iter().any(|(_, o)| o == option))
        .map(|(_, (name, _))| format!("{name:?}"))
        .collect();
    let listed = match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => names.concat(),
    };
    Err(Error::Choice {
        arg,
        value: value.into(),
        requirement: format!("must be {listed}"),
    }
    .into())
}

/// `heuristic`, as the renderer and the estimators take it (one default
/// for both, [`Heuristic::default`]: "power").
pub fn heuristic_arg(name: &str) -> PyResult<Heuristic> {
    choice(
        "heuristic",
        name,
        &[("power", Heuristic::Power), ("balance", Heuristic::Balance)],
    )
}
