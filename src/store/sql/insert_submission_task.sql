-- Records the job of one array task.
-- ?1: submission id, ?2: task, ?3: job id
INSERT INTO submission_tasks (submission_id, task, job_id) VALUES (?1, ?2, ?3)
