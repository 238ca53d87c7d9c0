# Per dataset: replay the inference of its assisted trials (PBA and CASA) with each
# trial's own settings (casa replay, docs/replay.md): per trial a table and two figures
# (the replay, with the logged alpha; the path over the task's intended path), and
# replay.csv with the largest difference from each log's beta, belief and alpha.
# After-learning trials run with the intents the dataset keeps in each participant's
# folder (casa replay --intents unset: docs/replay.md).


rule replay:
    input:
        raw_files,
        validation=PROCESSED / "{ds}" / "validation.csv",
        scene=dataset_scene,
    output:
        tables=directory(PROCESSED / "{ds}" / "replay"),
        figures=directory(FIGURES / "{ds}" / "replay"),
    log:
        "logs/replay/{ds}.log",
    conda:
        "../envs/casa.yaml"
    params:
        raw=lambda wildcards: RAW / wildcards.ds,
        allow_invalid=allow_invalid_flag,
    shell:
        "exec casa replay {params.raw} --out {output.tables} --figures {output.figures} "
        "--scene {input.scene} {params.allow_invalid} > {log} 2>&1"
