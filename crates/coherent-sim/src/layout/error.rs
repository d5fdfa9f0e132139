//! Why a layout could not be made.

/// Why a layout could not be made.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LayoutError(pub String);

impl std::fmt::Display for LayoutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for LayoutError {}

pub(super) fn err<T>(msg: String) -> Result<T, LayoutError> {
    Err(LayoutError(msg))
}
