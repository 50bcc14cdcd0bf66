-- Every job's id and stored spec, oldest first (re-keying).
-- no parameters
SELECT id, spec FROM jobs ORDER BY rowid
