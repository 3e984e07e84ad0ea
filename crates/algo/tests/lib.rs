//! Integration tests of sepg-algo, compiled into one binary (modules in `suite/`).
mod suite;
