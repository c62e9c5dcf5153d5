//! TOML case decks → validated [`crate::case::Case`].
