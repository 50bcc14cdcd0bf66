-- Switches the database to WAL mode; returns the journal mode now in effect.
-- no parameters
PRAGMA journal_mode = WAL
