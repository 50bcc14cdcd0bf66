-- Points the cluster tasks of a job at its new id.
-- ?1: old job id, ?2: new job id
UPDATE submission_tasks SET job_id = ?2 WHERE job_id = ?1
