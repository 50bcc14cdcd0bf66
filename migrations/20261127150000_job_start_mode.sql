-- The start mode of each job (`initial.start` of its spec: NULL where the spec leaves it out,
-- the default hot start) in a column of its own, read by the reports from the covering index
-- `jobs_report`. The index of 20261127130000 held `json_extract(spec, ...)` as an expression,
-- but SQLite evaluated the expression again on the job's row (its 1.5 kB spec parsed per job,
-- every page of `jobs` read) instead of taking it from the index. `upsert_job.sql` and
-- `copy_job_to_new_id.sql` set the column with the spec.

ALTER TABLE jobs ADD COLUMN start_mode TEXT;

UPDATE jobs SET start_mode = json_extract(spec, '$.scene.initial.start');

DROP INDEX jobs_report;
CREATE INDEX jobs_report ON jobs (id, status, attempts, last_error, wall_seconds, start_mode);
