# `snakemake --cores all robustness`: the simulated study once per modelling variant
# (config robustness.variants, casa_core/experiments/robustness.py) and the paper's claims under each.
# Each variant has its own config, logs, intents and tables below
# data/interim/robustness/<variant> and data/processed/robustness/<variant>: variants
# share nothing they write, and the same seeds. Part of the default target unless
# `--config simulate=false` (Snakefile).
# Each job's time goes to its benchmark file; after each variant a line of progress
# (variants done, time per variant, time left: casa progress) is printed and appended
# to data/processed/robustness/progress.log.
ROBUST_BENCHMARKS = BENCHMARKS / "robustness"


# A variant's participants are one job: casa simulate protocol of each in turn (the
# simulated study's job of study.smk, one participant after the other), so that a
# variant pays one process's start-up rather than one a participant. The power
# target's replicates run the same rule (power.smk).
VARIANT = ROBUST_INTERIM / "{variant}"


rule robustness_participants:
    input:
        config=variant_config_input,
        scene=variant_scene_input,
        population=OPERATOR_POPULATION,
    output:
        before=directory(
            expand(VARIANT / "raw" / "p{p}" / "before", p=ROBUST_PARTICIPANTS, allow_missing=True)
        ),
        after=directory(
            expand(VARIANT / "raw" / "p{p}" / "after", p=ROBUST_PARTICIPANTS, allow_missing=True)
        ),
        libraries=directory(
            expand(
                VARIANT / "intents" / "p{p}" / "{task}",
                p=ROBUST_PARTICIPANTS,
                task=UNKNOWN_TASKS,
                allow_missing=True,
            )
        ),
        rows=expand(
            VARIANT / "learning" / "p{p}_{task}.csv",
            p=ROBUST_PARTICIPANTS,
            task=UNKNOWN_TASKS,
            allow_missing=True,
        ),
        timings=expand(
            VARIANT / "learning" / "p{p}_{task}_timing.csv",
            p=ROBUST_PARTICIPANTS,
            task=UNKNOWN_TASKS,
            allow_missing=True,
        ),
    log:
        "logs/robustness/{variant}/participants.log",
    benchmark:
        ROBUST_BENCHMARKS / "{variant}" / "participants.tsv"
    conda:
        "../envs/casa.yaml"
    params:
        participants=" ".join(map(str, ROBUST_PARTICIPANTS)),
        before=participant_path(VARIANT, "raw", "p{p}", "before"),
        after=participant_path(VARIANT, "raw", "p{p}", "after"),
        library=participant_path(VARIANT, "intents", "p{p}"),
        rows=participant_paths(VARIANT, *(f"learning/p{{p}}_{task}.csv" for task in UNKNOWN_TASKS)),
        timings=participant_paths(
            VARIANT, *(f"learning/p{{p}}_{task}_timing.csv" for task in UNKNOWN_TASKS)
        ),
    shell:
        "exec casa simulate protocol --config {input.config} "
        "--participant {params.participants} --before {params.before} "
        "--library {params.library} --rows {params.rows} --timing-rows {params.timings} "
        "--out {params.after} > {log} 2>&1"


rule robustness_process:
    input:
        logs=expand(
            ROBUST_INTERIM / "{{variant}}" / "raw" / "p{p}" / "{stage}",
            p=ROBUST_PARTICIPANTS,
            stage=("before", "after"),
        ),
        scene=variant_scene_input,
    output:
        trials=ROBUST / "{variant}" / "trials.csv",
        steps=ROBUST / "{variant}" / "steps.csv",
        likert=ROBUST / "{variant}" / "likert.csv",
    log:
        "logs/robustness/{variant}/process.log",
    benchmark:
        ROBUST_BENCHMARKS / "{variant}" / "process.tsv"
    conda:
        "../envs/casa.yaml"
    params:
        raw=lambda wildcards: ROBUST_INTERIM / wildcards.variant / "raw",
        out=lambda wildcards: ROBUST / wildcards.variant,
    shell:
        "exec casa process {params.raw} --out {params.out} --scene {input.scene} "
        "--dataset simulated-{wildcards.variant} > {log} 2>&1"


rule robustness_stats:
    input:
        trials=ROBUST / "{variant}" / "trials.csv",
        likert=ROBUST / "{variant}" / "likert.csv",
    output:
        csv=ROBUST / "{variant}" / "stats.csv",
        md=ROBUST / "{variant}" / "stats.md",
    log:
        "logs/robustness/{variant}/stats.log",
    benchmark:
        ROBUST_BENCHMARKS / "{variant}" / "stats.tsv"
    conda:
        "../envs/casa.yaml"
    params:
        margins=margin_options,
        config=variant_config_input,
    shell:
        "exec casa stats --trials {input.trials} --likert {input.likert} {params.margins} "
        "--config {params.config} "
        "--out-csv {output.csv} --out-md {output.md} > {log} 2>&1"


# The expert case study and the arbitration comparison (C3, the expert rows) under the
# variant's inference; the expert keeps case_study.operator.
rule robustness_case_study:
    input:
        config=variant_config_input,
        scene=variant_scene_input,
    output:
        steps=ROBUST / "{variant}" / "case_study" / "steps.csv",
        arbitration=ROBUST / "{variant}" / "case_study" / "arbitration.csv",
        work=directory(ROBUST_INTERIM / "{variant}" / "case_study"),
    log:
        "logs/robustness/{variant}/case_study.log",
    benchmark:
        ROBUST_BENCHMARKS / "{variant}" / "case_study.tsv"
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa case-study --config {input.config} --work {output.work} "
        "--steps {output.steps} --arbitration {output.arbitration} > {log} 2>&1"


rule robustness_claims:
    input:
        trials=ROBUST / "{variant}" / "trials.csv",
        steps=ROBUST / "{variant}" / "steps.csv",
        likert=ROBUST / "{variant}" / "likert.csv",
        stats=ROBUST / "{variant}" / "stats.csv",
        case_steps=ROBUST / "{variant}" / "case_study" / "steps.csv",
        arbitration=ROBUST / "{variant}" / "case_study" / "arbitration.csv",
        config=variant_config_input,
    output:
        ROBUST / "{variant}" / "claims.csv",
    log:
        "logs/robustness/{variant}/claims.log",
    benchmark:
        ROBUST_BENCHMARKS / "{variant}" / "claims.tsv"
    conda:
        "../envs/casa.yaml"
    params:
        epsilon=config["simulation"]["epsilon"],
    shell:
        "exec casa report claims --trials {input.trials} --steps {input.steps} "
        "--stats {input.stats} --likert {input.likert} --case-steps {input.case_steps} "
        "--arbitration {input.arbitration} --variant {wildcards.variant} "
        "--config {input.config} --epsilon {params.epsilon} --out {output} > {log} 2>&1"


rule robustness_table:
    input:
        claims=expand(ROBUST / "{variant}" / "claims.csv", variant=VARIANTS),
        config=CONFIG_FILE,
    output:
        csv=ROBUST / "claims.csv",
        md=ROBUST / "results.md",
        pdf=FIGURES / "robustness.pdf",
        png=FIGURES / "robustness.png",
    log:
        "logs/robustness/table.log",
    conda:
        "../envs/casa.yaml"
    params:
        stem=FIGURES / "robustness",
        provenance=provenance_options,
    shell:
        "exec casa report robustness --claims {input.claims} --out-csv {output.csv} "
        "--out-md {output.md} --figure {params.stem} {params.provenance} > {log} 2>&1"


# On the machine running Snakemake, so that the line shows beside Snakemake's own.
localrules:
    robustness_progress,


rule robustness_progress:
    input:
        ROBUST / "{variant}" / "claims.csv",
    output:
        ROBUST_INTERIM / "{variant}" / "progress.txt",
    log:
        "logs/robustness/{variant}/progress.log",
    conda:
        "../envs/casa.yaml"
    params:
        config=CONFIG_FILE,
        log=ROBUST / "progress.log",
    shell:
        "exec casa progress robustness --config {params.config} --done {wildcards.variant} "
        "--out {output} --append {params.log} 2> {log}"


rule robustness:
    input:
        rules.robustness_table.output,
        expand(ROBUST_INTERIM / "{variant}" / "progress.txt", variant=VARIANTS),
