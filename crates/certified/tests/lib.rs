//! Integration tests of `sepg-certified`, compiled as a single binary.

mod checks;
