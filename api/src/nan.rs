//! NaN as JSON `null`: serde_json writes a non-finite `f64` as `null`; [`f64_or_nan`] reads
//! such a `null` back as NaN, so history rows round-trip through JSON (worker uploads, the
//! MCAP channels, API answers) without a mirror type.

use serde::{Deserialize, Deserializer};

/// NaN, the serde default of a number a row may lack (rows written before the column).
pub fn nan() -> f64 {
    f64::NAN
}

/// Deserialize an `f64` that may be `null` (read as NaN).
pub fn f64_or_nan<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

#[cfg(test)]
mod tests {
    use crate::results::{CrackTipRow, EnergyRow};

    #[test]
    fn rows_round_trip_nan_through_json() {
        let row = CrackTipRow {
            k1: f64::NAN,
            j1: 3.5,
            growing: true,
            ..CrackTipRow::default()
        };
        let text = serde_json::to_string(&row).unwrap_or_default();
        assert!(text.contains("\"k1\":null"), "{text}");
        let back: CrackTipRow = serde_json::from_str(&text).unwrap_or_default();
        assert!(back.k1.is_nan());
        assert_eq!(back.j1, 3.5);
        assert!(back.growing);
        let e = EnergyRow {
            total_error: f64::NAN,
            fracture: 2.0,
            ..EnergyRow::default()
        };
        let back: EnergyRow = serde_json::from_str(&serde_json::to_string(&e).unwrap_or_default())
            .unwrap_or_default();
        assert!(back.total_error.is_nan());
    }
}
