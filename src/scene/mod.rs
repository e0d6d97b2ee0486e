//! TOML scene files (serde, deny_unknown_fields), validated into models.
