-- The versions of the migrations applied to this database (read-only opens compare them with
-- the embedded ones).
-- no parameters
SELECT version FROM _sqlx_migrations WHERE success ORDER BY version
