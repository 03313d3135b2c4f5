//! vas wire types and service names.
