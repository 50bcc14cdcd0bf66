-- Records what collection found for a task.
-- ?1: submission id, ?2: task, ?3: state, ?4: message
UPDATE submission_tasks SET state = ?3, message = ?4
WHERE submission_id = ?1 AND task = ?2
