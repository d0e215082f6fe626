//! Markdown and CSV tables and the number format of their cells.

/// The header row and the separator row of a Markdown table.
pub fn markdown_header<S: AsRef<str>>(header: &[S]) -> String {
    let names: Vec<&str> = header.iter().map(AsRef::as_ref).collect();
    format!(
        "| {} |\n|{}\n",
        names.join(" | "),
        " --- |".repeat(names.len())
    )
}

/// One body row of a Markdown table.
pub fn markdown_row<S: AsRef<str>>(cells: &[S]) -> String {
    let cells: Vec<&str> = cells.iter().map(AsRef::as_ref).collect();
    format!("| {} |\n", cells.join(" | "))
}

/// A Markdown table from a header and rows.
pub fn markdown_table<S: AsRef<str>>(header: &[S], rows: &[Vec<String>]) -> String {
    let mut s = markdown_header(header);
    for r in rows {
        s.push_str(&markdown_row(r));
    }
    s
}

/// A CSV line (fields must not contain commas; the callers' fields are numbers and names).
pub fn csv_line<S: AsRef<str>>(fields: &[S]) -> String {
    let fields: Vec<&str> = fields.iter().map(AsRef::as_ref).collect();
    let mut s = fields.join(",");
    s.push('\n');
    s
}

/// Format a float for a table with `digits` significant digits; "–" for NaN.
pub fn sig(x: f64, digits: usize) -> String {
    if !x.is_finite() {
        return "–".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let mag = x.abs().log10().floor() as i32;
    let decimals = (digits as i32 - 1 - mag).max(0) as usize;
    format!("{x:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_and_numbers() {
        assert_eq!(
            markdown_table(&["a", "b"], &[vec!["1".into(), String::new()]]),
            "| a | b |\n| --- | --- |\n| 1 |  |\n"
        );
        assert_eq!(csv_line(&["x", "2"]), "x,2\n");
        assert_eq!(sig(1234.4, 3), "1234");
        assert_eq!(sig(0.012345, 3), "0.0123");
        assert_eq!(sig(f64::NAN, 3), "–");
    }
}
