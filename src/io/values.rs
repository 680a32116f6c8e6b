//! The values of the command line's options that are not names (contract section 5, "Common
//! options"): seconds, tolerances, sizes in bytes and 3-vectors. Each parser returns the value or
//! a one-line reason (the form `clap` prints as a usage error).

/// `none` (infinity: no limit), or a positive finite number of seconds (`--max-seconds`).
///
/// ```
/// use rotavg::io::values::parse_seconds;
/// assert_eq!(parse_seconds("none"), Ok(f64::INFINITY));
/// assert_eq!(parse_seconds("2.5"), Ok(2.5));
/// assert!(parse_seconds("0").is_err() && parse_seconds("inf").is_err());
/// ```
pub fn parse_seconds(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        _ if text.eq_ignore_ascii_case("none") => Ok(f64::INFINITY),
        Ok(t) if t.is_finite() && t > 0.0 => Ok(t),
        _ => Err(format!(
            "`{text}` is not a positive number of seconds or `none`"
        )),
    }
}

/// A positive, finite tolerance (`--rotation-tolerance`).
///
/// ```
/// use rotavg::io::values::parse_tolerance;
/// assert_eq!(parse_tolerance("1e-6"), Ok(1e-6));
/// assert!(parse_tolerance("0").is_err() && parse_tolerance("nan").is_err());
/// ```
pub fn parse_tolerance(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 => Ok(t),
        _ => Err(format!("`{text}` is not a positive number")),
    }
}

/// A size of at least one byte with an optional K, M, G or T suffix (powers of 1024; a trailing
/// `B` or `iB` is accepted; `--max-memory`).
///
/// ```
/// use rotavg::io::values::parse_bytes;
/// assert_eq!(parse_bytes("4G"), Ok(4 << 30));
/// assert_eq!(parse_bytes("512MiB"), Ok(512 << 20));
/// assert_eq!(parse_bytes("1.5k"), Ok(1536));
/// assert_eq!(parse_bytes("1000"), Ok(1000));
/// for bad in ["0", "-3G", "4X", "nan", "1e30T"] {
///     assert!(parse_bytes(bad).is_err(), "{bad}");
/// }
/// ```
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let upper = text.trim().to_ascii_uppercase();
    let stem = upper
        .strip_suffix("IB")
        .or_else(|| upper.strip_suffix('B'))
        .unwrap_or(&upper);
    let (number, shift) = match stem.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => match "KMGT".find(c) {
            Some(k) => (&stem[..i], 10 * (k + 1)),
            None => return Err(format!("`{text}`: unknown unit (use K, M, G or T)")),
        },
        _ => (stem, 0),
    };
    let scale = (1u64 << shift) as f64;
    match number.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 1.0 && v * scale < 2f64.powi(63) => Ok((v * scale) as u64),
        _ => Err(format!("`{text}` is not a size of at least 1 byte")),
    }
}

/// `X,Y,Z`: three finite numbers (`--world-down`).
///
/// ```
/// use rotavg::io::values::parse_vector;
/// assert_eq!(parse_vector("0, 1,0"), Ok([0.0, 1.0, 0.0]));
/// assert!(parse_vector("1,2").is_err() && parse_vector("1,2,inf").is_err());
/// ```
pub fn parse_vector(text: &str) -> Result<[f64; 3], String> {
    let parts: Vec<f64> = text
        .split(',')
        .map(|p| p.trim().parse::<f64>().map_err(|e| format!("`{p}`: {e}")))
        .collect::<Result<_, _>>()?;
    match parts[..] {
        [x, y, z] if parts.iter().all(|v| v.is_finite()) => Ok([x, y, z]),
        _ => Err("expected three finite numbers X,Y,Z".into()),
    }
}
