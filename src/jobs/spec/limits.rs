//! `limits`: what a job may use in the service, at most the server's own budgets
//! per job (`serve --job-memory`, `--job-seconds`, `--job-disk`; docs/isolation.md).
//! Sizes are bytes, as a number or as text with a binary (`KiB` … `TiB`) or
//! decimal (`kB` … `TB`) suffix.

use super::SpecError;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `limits`: every field optional; the CLI runs without them.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct LimitsSpec {
    /// (Addition) the job's memory budget (its process's data segment): bytes, or
    /// text such as `"512MiB"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub memory: Option<Size>,
    /// (Addition) the wall-clock budget of one attempt, in seconds.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub seconds: Option<f64>,
    /// (Addition) what the job may store (checkpoints, result files, history):
    /// bytes, or text such as `"2GiB"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub disk: Option<Size>,
}

/// A size: bytes, or text with a unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum Size {
    Bytes(u64),
    Text(String),
}

/// `limits` with its sizes in bytes.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Limits {
    pub memory: Option<u64>,
    pub seconds: Option<f64>,
    pub disk: Option<u64>,
}

impl LimitsSpec {
    pub fn is_empty(&self) -> bool {
        *self == LimitsSpec::default()
    }

    /// The limits in bytes and seconds, or the field that is wrong.
    pub fn resolve(&self) -> Result<Limits, SpecError> {
        let size = |field: &str, s: &Option<Size>| -> Result<Option<u64>, SpecError> {
            match s {
                None => Ok(None),
                Some(Size::Bytes(0)) => Err(SpecError::new(field, "must be a positive size, got 0")),
                Some(Size::Bytes(b)) => Ok(Some(*b)),
                Some(Size::Text(t)) => parse_size(t).map(Some).map_err(|e| SpecError::new(field, e)),
            }
        };
        let seconds = match self.seconds {
            Some(s) if !(s.is_finite() && s > 0.0) => {
                return Err(SpecError::new("limits.seconds", format!("must be a positive number of seconds, got {s}")))
            }
            s => s,
        };
        Ok(Limits { memory: size("limits.memory", &self.memory)?, seconds, disk: size("limits.disk", &self.disk)? })
    }
}

/// A size in bytes, with an optional binary (`KiB`, `MiB`, `GiB`, `TiB`) or
/// decimal (`kB`, `MB`, `GB`, `TB`) suffix: `512MiB`, `2GiB`, `1000000`.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(t.len());
    let (number, unit) = (&t[..split], t[split..].trim());
    let n: f64 = number.parse().map_err(|_| format!("expected a size such as 512MiB or 2GiB, got {text:?}"))?;
    let scale: u64 = match unit {
        "" | "B" => 1,
        "KiB" | "K" => 1 << 10,
        "MiB" | "M" => 1 << 20,
        "GiB" | "G" => 1 << 30,
        "TiB" | "T" => 1 << 40,
        "kB" | "KB" => 1_000,
        "MB" => 1_000_000,
        "GB" => 1_000_000_000,
        "TB" => 1_000_000_000_000,
        _ => return Err(format!("unknown unit {unit:?} in {text:?} (use B, KiB, MiB, GiB, TiB, kB, MB, GB or TB)")),
    };
    let bytes = n * scale as f64;
    if !bytes.is_finite() || bytes < 1.0 || bytes > u64::MAX as f64 {
        return Err(format!("expected a positive size, got {text:?}"));
    }
    Ok(bytes as u64)
}

/// A size for messages: `2 GiB`, `512 MiB`, `1.50 GiB`, `1000 B`.
pub fn format_size(bytes: u64) -> String {
    const UNITS: [(&str, u64); 4] = [("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)];
    for (name, scale) in UNITS {
        if bytes >= scale {
            let v = bytes as f64 / scale as f64;
            return if (v - v.round()).abs() < 0.005 {
                format!("{} {name}", v.round())
            } else {
                format!("{v:.2} {name}")
            };
        }
    }
    format!("{bytes} B")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_print() {
        assert_eq!(parse_size("512MiB"), Ok(512 << 20));
        assert_eq!(parse_size("2GiB"), Ok(2 << 30));
        assert_eq!(parse_size("1.5 GiB"), Ok(3 << 29));
        assert_eq!(parse_size("1000000"), Ok(1_000_000));
        assert_eq!(parse_size("3MB"), Ok(3_000_000));
        assert!(parse_size("12 parsecs").unwrap_err().contains("unknown unit"));
        assert!(parse_size("-3MiB").is_err());
        assert!(parse_size("0").is_err());
        assert_eq!(format_size(2 << 30), "2 GiB");
        assert_eq!(format_size(3 << 29), "1.50 GiB");
        assert_eq!(format_size(512 << 20), "512 MiB");
        assert_eq!(format_size(1000), "1000 B");
    }

    #[test]
    fn limits_resolve_or_name_their_field() {
        let spec =
            LimitsSpec { memory: Some(Size::Text("1GiB".into())), seconds: Some(60.0), disk: Some(Size::Bytes(7)) };
        assert_eq!(spec.resolve().unwrap(), Limits { memory: Some(1 << 30), seconds: Some(60.0), disk: Some(7) });
        let bad = LimitsSpec { memory: Some(Size::Text("lots".into())), ..LimitsSpec::default() };
        assert_eq!(bad.resolve().unwrap_err().field, "limits.memory");
        let bad = LimitsSpec { seconds: Some(-1.0), ..LimitsSpec::default() };
        assert_eq!(bad.resolve().unwrap_err().field, "limits.seconds");
    }
}
