//! PLACEHOLDER: filled by the gen-city helper.
