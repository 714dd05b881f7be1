//! Generated tables of published CIE data. Regenerate with `tools/gen_cie_tables.py` (its header
//! names the source package and version); never edit by hand.
#[rustfmt::skip]
#[allow(clippy::excessive_precision, clippy::unreadable_literal, clippy::approx_constant)]
pub mod cie_tables;
