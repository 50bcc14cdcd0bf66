-- Copies the write-ahead log into the database and truncates the log to zero bytes.
PRAGMA wal_checkpoint(TRUNCATE)
