//! vas client library.
