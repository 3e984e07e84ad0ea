//! Integration tests of `sepg-bounds`, compiled as a single binary.

mod checks;
