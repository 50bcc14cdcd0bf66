-- Number of run rows per job.
-- no parameters
SELECT job_id, count(*) FROM runs GROUP BY job_id ORDER BY job_id
