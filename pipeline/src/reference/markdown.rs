//! What every generated page shares: its first line and its table cells.

/// The line every generated page starts with.
pub(super) const GENERATED: &str =
    "<!-- Generated from the code by `pipeline::reference`; do not edit. \
Rewrite with: RIBBAR_WRITE_REFERENCE=1 cargo test -p pipeline --test suite reference:: -->";

/// Text for a Markdown table cell: one line, pipes escaped.
pub(super) fn cell(text: &str) -> String {
    text.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .replace('|', "\\|")
}
