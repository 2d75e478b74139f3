//! VTU output of fields.
