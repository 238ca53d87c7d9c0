# Per dataset: check every raw file against casa-trial/1, then build its tables.
# Raw files are only read. A bad file stops this dataset (every problem is listed
# in the log and on the console); with allow_invalid=true bad files are excluded
# and listed in validation.csv. The console shows every problem (tee); exec keeps the
# casa command a direct child of Snakemake (workflow/rules/common.smk).


rule validate:
    input:
        raw_files,
    output:
        PROCESSED / "{ds}" / "validation.csv",
    log:
        "logs/validate/{ds}.log",
    conda:
        "../envs/casa.yaml"
    params:
        raw=lambda wildcards: RAW / wildcards.ds,
        allow_invalid=allow_invalid_flag,
    shell:
        "exec casa validate {params.raw} --report {output} {params.allow_invalid} "
        "> >(tee {log}) 2>&1"


rule process:
    input:
        raw_files,
        validation=PROCESSED / "{ds}" / "validation.csv",
        scene=dataset_scene,
    output:
        trials=PROCESSED / "{ds}" / "trials.csv",
        steps=PROCESSED / "{ds}" / "steps.csv",
        likert=PROCESSED / "{ds}" / "likert.csv",
    log:
        "logs/process/{ds}.log",
    conda:
        "../envs/casa.yaml"
    params:
        raw=lambda wildcards: RAW / wildcards.ds,
        out=lambda wildcards: PROCESSED / wildcards.ds,
        allow_invalid=allow_invalid_flag,
    shell:
        "exec casa process {params.raw} --out {params.out} --scene {input.scene} "
        "--dataset {wildcards.ds} {params.allow_invalid} > {log} 2>&1"


# A dataset folder whose name is refused (common.smk: discover_datasets): a job that
# fails saying why and how to rename it, so that the other datasets build first.
rule refused_dataset:
    output:
        REFUSED_LOGS / "{refused}.refused",
    log:
        REFUSED_LOGS / "{refused}.log",
    conda:
        "../envs/casa.yaml"
    params:
        reason=lambda wildcards: shlex.quote(REFUSED[wildcards.refused]),
    shell:
        "printf '%s\\n' {params.reason} | tee {log} >&2; exit 1"
