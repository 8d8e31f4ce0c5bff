//! The timestamps shown to users: RFC 3339 UTC to the millisecond.

/// RFC 3339 UTC from the system clock (timestamps shown to users; leases use the
/// database's clock).
pub fn now() -> String {
    rfc3339_ago(0.0)
}

/// RFC 3339 UTC of `ago` seconds before now (fixed width: such strings compare as
/// their times).
pub fn rfc3339_ago(ago: f64) -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64() - ago)
        .unwrap_or(0.0)
        .max(0.0);
    rfc3339_at(secs)
}

/// RFC 3339 UTC of `secs` seconds after the Unix epoch, to the millisecond
/// (rounded in whole milliseconds first: a time 0.4 ms before a minute is that
/// minute, never second 60).
fn rfc3339_at(secs: f64) -> String {
    let ms = (secs * 1000.0).round() as i64;
    let days = ms.div_euclid(86_400_000);
    let rem = ms - days * 86_400_000;
    let (h, m, s, milli) = (rem / 3_600_000, rem / 60_000 % 60, rem / 1000 % 60, rem % 1000);
    // civil from days (Howard Hinnant's algorithm)
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let mo = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + if mo <= 2 { 1 } else { 0 };
    format!("{y:04}-{mo:02}-{d:02}T{h:02}:{m:02}:{s:02}.{milli:03}Z")
}

#[cfg(test)]
mod tests {
    use super::rfc3339_at;

    /// Times within half a millisecond of a minute, an hour and a year are that
    /// minute (the schemathesis run caught `16:08:60.000Z`).
    #[test]
    fn timestamps_round_into_the_next_minute_not_second_60() {
        assert_eq!(rfc3339_at(0.0), "1970-01-01T00:00:00.000Z");
        assert_eq!(rfc3339_at(59.9996), "1970-01-01T00:01:00.000Z");
        assert_eq!(rfc3339_at(3599.9997), "1970-01-01T01:00:00.000Z");
        assert_eq!(rfc3339_at(1_798_761_599.999_9), "2027-01-01T00:00:00.000Z");
        assert_eq!(rfc3339_at(1_796_313_540.25), "2026-12-03T15:59:00.250Z");
    }
}
