//! Cross-section and history pictures (PNG, embedded font).
