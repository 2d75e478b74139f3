//! What every generated page shares: its first line and its table cells.

/// The line every generated page starts with.
pub(super) const GENERATED: &str =
    "<!-- Generated from the code by `pipeline::reference`; do not edit. \
Rewrite with: RIBBAR_WRITE_REFERENCE=1 cargo test -p pipeline --test suite reference:: -->";

/// Text for a Markdown table cell: one line, pipes escaped, and a `<`
/// that would open an HTML tag outside code spans written as `&lt;`, so
/// that `WORK/<study>` is not read as one (`0 < a` stays as it is).
pub(super) fn cell(text: &str) -> String {
    let one_line = text.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut out = String::with_capacity(one_line.len());
    let mut in_code = false;
    let mut chars = one_line.chars().peekable();
    while let Some(c) = chars.next() {
        let opens_tag = chars
            .peek()
            .is_some_and(|n| n.is_ascii_alphabetic() || matches!(n, '/' | '!'));
        match c {
            '`' => {
                in_code = !in_code;
                out.push(c);
            }
            '|' => out.push_str("\\|"),
            '<' if !in_code && opens_tag => out.push_str("&lt;"),
            _ => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    /// Cells are one line; pipes are escaped everywhere, `<` outside code.
    #[test]
    fn cells_are_one_line_without_html() {
        assert_eq!(
            super::cell("a  |\n b `WORK/<s>` WORK/<s> 0 < a"),
            "a \\| b `WORK/<s>` WORK/&lt;s> 0 < a"
        );
    }
}
