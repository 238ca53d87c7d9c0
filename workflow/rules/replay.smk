# Per dataset: replay the inference of its assisted trials (PBA and CASA) with each
# trial's own settings (casa replay, docs/replay.md): one table and one figure per
# trial, and replay.csv with the largest difference from each log's beta, belief and
# alpha. The simulated study's learned intents are passed from its library.


rule replay:
    input:
        raw_files,
        replay_intents,
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
        intents=lambda wildcards: f"--intents {INTENTS}" if wildcards.ds in GENERATED else "",
        allow_invalid=allow_invalid_flag,
    shell:
        "exec casa replay {params.raw} --out {output.tables} --figures {output.figures} "
        "--scene {input.scene} {params.intents} {params.allow_invalid} > {log} 2>&1"
