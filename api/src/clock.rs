//! Wall-clock times as the service writes them: RFC 3339 UTC with exactly three fraction
//! digits (`2026-12-02T04:45:31.800Z`). The width is fixed, so two times compare as text in
//! time order (the store's queries, `started_at <= finished_at` in a run's provenance); the
//! `time` crate's well-known RFC 3339 format trims trailing zeros and would not.

/// A UTC time as the service writes it (the store's columns, a run's provenance): RFC 3339
/// with milliseconds (`2026-12-02T04:45:31.123Z`), which sorts as text in time order.
pub fn time_text(t: time::OffsetDateTime) -> String {
    let t = t.to_offset(time::UtcOffset::UTC);
    format!(
        "{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{:03}Z",
        t.year(),
        u8::from(t.month()),
        t.day(),
        t.hour(),
        t.minute(),
        t.second(),
        t.millisecond()
    )
}

/// Now, as [`time_text`] writes it (the store binds it into its queries, so every timestamp
/// comes from the service's clock, whichever the database).
pub fn now_text() -> String {
    time_text(time::OffsetDateTime::now_utc())
}

/// Read back a time [`time_text`] wrote; `None` if it is not one.
pub fn parse_time_text(s: &str) -> Option<time::OffsetDateTime> {
    let b = s.as_bytes();
    if b.len() != 24 || b[4] != b'-' || b[7] != b'-' || b[10] != b'T' || b[23] != b'Z' {
        return None;
    }
    let n = |r: std::ops::Range<usize>| s.get(r)?.parse::<u32>().ok();
    let month = time::Month::try_from(u8::try_from(n(5..7)?).ok()?).ok()?;
    let date =
        time::Date::from_calendar_date(i32::try_from(n(0..4)?).ok()?, month, n(8..10)? as u8)
            .ok()?;
    let t = time::Time::from_hms_milli(
        n(11..13)? as u8,
        n(14..16)? as u8,
        n(17..19)? as u8,
        n(20..23)? as u16,
    )
    .ok()?;
    Some(time::PrimitiveDateTime::new(date, t).assume_utc())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whole seconds keep their three zeros, so `…:30.800Z` sorts before `…:30.877Z` (the
    /// trimmed `…:30.8Z` sorted after it and failed a run's provenance check); round trip.
    #[test]
    fn fixed_width_sorts_as_time_and_reads_back() {
        let base = time::OffsetDateTime::from_unix_timestamp(1_796_000_000).expect("t");
        let a = time_text(base + time::Duration::milliseconds(800));
        let b = time_text(base + time::Duration::milliseconds(877));
        let c = time_text(base + time::Duration::seconds(1));
        assert!(a.ends_with(".800Z") && c.ends_with(".000Z"), "{a} {c}");
        assert!(a < b && b < c, "{a} {b} {c}");
        assert_eq!(
            parse_time_text(&b),
            Some(base + time::Duration::milliseconds(877))
        );
        assert_eq!(now_text().len(), 24);
        assert_eq!(parse_time_text("2026-12-02T04:45:31.8Z"), None);
    }

    #[test]
    fn times_are_written_and_read_back_to_the_millisecond() {
        let t = time::OffsetDateTime::from_unix_timestamp_nanos(1_796_186_731_123_456_789)
            .expect("a time");
        let s = time_text(t);
        assert_eq!(s, "2026-12-02T04:45:31.123Z");
        let back = parse_time_text(&s).expect("parses");
        assert_eq!(back.unix_timestamp_nanos(), 1_796_186_731_123_000_000);
        assert!(parse_time_text("2026-12-02 04:45:31").is_none());
        assert!(parse_time_text("2026-13-02T04:45:31.123Z").is_none());
    }
}
